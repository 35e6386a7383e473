/* The FMI 2.0 co-simulation layer of the native FMU (fmu_build --native): contact_fmu's
 * body mode on the compiled stepper (stepper.c, included: one translation unit), its
 * contact mode (fmu/contact_model.py: the thin-layer law, with a spin input by the strip
 * march on the law's spin grid, and its analytic directional derivatives) and its
 * rigid_body mode (fmu/rigid_body.py), with no Python anywhere (CF_MODE picks one).
 *
 * The body model is the one of fmu/body_model.py on its compiled paths: the thin-layer
 * law (layer.py; its contact ellipse and constants, Eqs. 33-34, derived here from the
 * parameters and the load P: cf_layer_law), Lobatto IIIC or SDIRK2 (the String parameter
 * scheme where the FMU offers both), methods "full" and "quasistationary"; vx the only
 * stage unknown (vy zero or held at a ratio, no spin:
 * cf_advance) or Vy and/or Omega_z as unknowns too (Eqs. 10-11: cf_advance_vector, the
 * law's spin by the strip march on its grid, built here for each load: cf_grid_build).
 * The build refuses every other model (fmu_build/native_fmu.py). The variables, their
 * ranges, starts and the check messages come from contact_fmu/fmu/variables.py through
 * the generated cf_model.h; the constants the Python integrator uses travel in it too.
 *
 * Behaviour, the pythonfmu FMU's (contact_fmu/fmu/slave.py, docs/reliability.md):
 * - an inadmissible value (non-finite, out of its declared range) answers fmi2Error at
 *   its setter and is held, with a logged error naming the variable and the value;
 *   while it is held every doStep answers fmi2Discard with that message and changes
 *   nothing, getReal of it (and, in contact mode, of the outputs) fmi2Error; once
 *   corrected the instance steps normally;
 * - doStep before a successful exitInitializationMode or after fmi2Terminate:
 *   fmi2Error; with a step not in (0, inf) or not at the FMU's time (64 ulp of t):
 *   fmi2Discard; loads beyond integrator.LOAD_LIMIT mu P: fmi2Discard;
 * - a step with no stage root (loads beyond mu P with an eta = inf body; a stage whose
 *   Newton iteration does not converge is bracketed and closed by brentq, as in Python)
 *   or with non-finite outputs: fmi2Discard, state unchanged;
 * - parameters are fixed once the model is set up: setting one then is refused
 *   (fmi2Error, the value kept); setting an output likewise. mu is tunable: the law is
 *   rebuilt at the next step (or, in contact mode, the next output read);
 * - a model that cannot be set up (bad parameters): fmi2Error at
 *   exitInitializationMode, with the reason.
 * Memory comes from the importer's callbacks; there is no mutable global: instances
 * are independent, also on several threads. The logger never gets user text as its
 * format. FMU state: the whole instance core (plain data), serialized with a format
 * version, the GUID, the length and a checksum; foreign or damaged bytes are refused.
 */
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "stepper.c"

/* ---- the variables (cf_model.h, generated from variables.py) ---------------------- */
enum { K_PARAMETER, K_INPUT, K_OUTPUT };
enum { T_REAL, T_INTEGER, T_STRING };

/* the parameters and inputs the model reads, by role */
enum {
    R_MU, R_RX, R_RY, R_K1, R_K2, R_KB, R_KS, R_M, R_IY, R_VY_RATIO, R_VX0, R_SLIP0,
    R_H_MAX, R_METHOD, R_P, R_FX_EX, R_MY_EX,
    R_VX, R_VY, R_OMEGA_Y, R_OMEGA_Z, R_TX, /* contact-mode kinematics, rigid_body's Tx */
    R_IZ, R_VY0, R_OMEGA_Z0, R_SPIN_RATIO, R_FY_EX, R_MZ_EX, /* Eqs. (10)-(11) */
    R_SCHEME, /* the integrator's scheme (a String, as R_METHOD) */
    R_COUNT
};
/* the modes (CF_MODE): fmu/body_model.py, contact_model.py, rigid_body.py */
enum { MODE_BODY, MODE_CONTACT, MODE_RIGID };
#define R_OUT 1000 /* outputs: R_OUT + the index in cf_body.out */

typedef struct {
    const char *name;
    int kind, type, role;
    double start;
    double lo, hi;             /* declared range (-inf, inf where none) */
    int open_lo;               /* lo itself excluded */
    const char *lo_req, *hi_req; /* Var.check's requirement texts: "> 0", "<= 1" */
    double fix;                  /* a value the build fixes (ModelConfig.fixed) ... */
    const char *fix_req;         /* ... and the requirement text, or NULL */
} cf_var;

#include "cf_model.h"

#define N_METHODS 2
static const char *const METHOD_NAMES[N_METHODS] = {"full", "quasistationary"};
#define N_SCHEMES 2
static const char *const SCHEME_NAMES[N_SCHEMES] = {"lobatto3c", "sdirk2"}; /* integrator */
#define METHOD_TEXT 64

/* ---- the instance ------------------------------------------------------------------ */
enum { PH_INSTANTIATED, PH_INIT, PH_STEP, PH_TERMINATED };

/* Everything an FMU state holds: plain data, no pointer that is not NULL. */
typedef struct {
    double val[R_COUNT];          /* parameters and inputs by role */
    double var[CF_N_VARS];        /* every Real/Integer variable's value, by vr */
    unsigned bad[CF_N_VARS];      /* 0, or the order in which the value became bad */
    unsigned next_bad;
    int method;                   /* index into METHOD_NAMES, -1: not a method */
    char method_text[METHOD_TEXT]; /* the string set (cut at METHOD_TEXT - 1) */
    int scheme;                   /* index into SCHEME_NAMES, -1: not a scheme */
    char scheme_text[METHOD_TEXT]; /* the string set, as method_text */
    double time;
    int phase, built;
    int init_tried;               /* fmi2ExitInitializationMode was called */
    int dirty;                    /* contact mode: inputs set since the outputs */
    double rb_Vx, rb_Omega_y;     /* rigid_body mode's state */
    cf_vstate vs;                 /* body mode with Vy and/or Omega_z as unknowns */
    double P_law;                 /* the load the law's constants are for */
    cf_params p;
    cf_state s;
    cf_body b;
} cf_core;

/* the spin grid of the vector path and of the contact mode's spin input (layer._Grid of
 * SPIN_GRID): a function of the law at its load (a1, a2, p0, mu, kb + ks), rebuilt when
 * one of them changes (a new load, a tuned mu, a reset), not part of the FMU state */
#define GRID_N (CF_SPIN_NX * CF_SPIN_NY)
#define CF_GRID ((CF_VECTOR || CF_CONTACT_SPIN) && !CF_TABLE)
typedef struct {
    double key[5];                /* the law it is for: a1, a2, p0, mu, k (NaN: none yet) */
    cf_strips strips;
    double x[CF_SPIN_NX], y[CF_SPIN_NY], dist[GRID_N], mid[GRID_N], cap[GRID_N], w[GRID_N];
    unsigned char inside[GRID_N];
    double tau[2 * GRID_N];       /* scratch of the adhesion's march */
    unsigned char slip[GRID_N];
} spin_grid;

typedef struct {
    fmi2CallbackFunctions cb;
    char *name;
    int logging;
    cf_core c;
    char method_out[METHOD_TEXT]; /* what getString hands out */
    char scheme_out[METHOD_TEXT];
    spin_grid *grid;              /* CF_GRID only */
    double *table;                /* CF_TABLE: axes then patch coefficients (resource) */
    unsigned long served;         /* the FMU's outputs, a bit per index of cf_body.out */
    cf_core **states;             /* the live FMU states handed out: an open-addressing */
    size_t n_states, cap_states;  /* set of pointers (NULL: empty slot), cap a power of 2 */
} Inst;

/* the creep-force table's arrays into p (after set_constants) */
static void attach_table(const Inst *I, cf_params *p) {
    if (!CF_TABLE || I->table == NULL) return;
    p->ax1 = I->table;
    p->ax2 = p->ax1 + CF_T_N1;
    p->ax3 = p->ax2 + CF_T_N2;
    p->coef = p->ax3 + CF_T_N3;
    p->n1 = CF_T_N1, p->n2 = CF_T_N2, p->n3 = CF_T_N3;
    p->ext1 = p->ax1[CF_T_N1 - 1], p->ext2 = p->ax2[CF_T_N2 - 1], p->ext3 = p->ax3[CF_T_N3 - 1];
}

/* ---- messages ---------------------------------------------------------------------- */
/* Python's repr of a float: the shortest digits that read back, its layout */
static void py_repr(double x, char *out, size_t n) {
    if (isnan(x)) {
        snprintf(out, n, "nan");
        return;
    }
    if (isinf(x)) {
        snprintf(out, n, x < 0 ? "-inf" : "inf");
        return;
    }
    if (x == 0.0) {
        snprintf(out, n, signbit(x) ? "-0.0" : "0.0");
        return;
    }
    char tmp[48];
    for (int prec = 0; prec <= 17; prec++) {
        snprintf(tmp, sizeof tmp, "%.*e", prec, x);
        if (strtod(tmp, NULL) == x) break;
    }
    /* tmp: [-]d[.ddd]e[+-]XX */
    char digits[24];
    int nd = 0, neg = tmp[0] == '-';
    const char *q = tmp + neg;
    for (; *q && *q != 'e'; q++)
        if (*q >= '0' && *q <= '9' && nd < 23) digits[nd++] = *q;
    int e = *q == 'e' ? atoi(q + 1) : 0;
    while (nd > 1 && digits[nd - 1] == '0') nd--;
    digits[nd] = '\0';
    int decpt = e + 1;
    char body[64];
    size_t k = 0;
    if (-4 < decpt && decpt <= 16) {
        if (decpt <= 0) {
            k += (size_t)snprintf(body + k, sizeof body - k, "0.");
            for (int i = 0; i < -decpt; i++) body[k++] = '0';
            k += (size_t)snprintf(body + k, sizeof body - k, "%s", digits);
        } else if (decpt >= nd) {
            k += (size_t)snprintf(body + k, sizeof body - k, "%s", digits);
            for (int i = nd; i < decpt; i++) body[k++] = '0';
            k += (size_t)snprintf(body + k, sizeof body - k, ".0");
        } else {
            k += (size_t)snprintf(body + k, sizeof body - k, "%.*s.%s", decpt, digits,
                                  digits + decpt);
        }
    } else {
        k += (size_t)snprintf(body + k, sizeof body - k, "%c", digits[0]);
        if (nd > 1) k += (size_t)snprintf(body + k, sizeof body - k, ".%s", digits + 1);
        snprintf(body + k, sizeof body - k, "e%c%02d", e < 0 ? '-' : '+', e < 0 ? -e : e);
    }
    snprintf(out, n, "%s%s", neg ? "-" : "", body);
}

static const char *category(fmi2Status s) {
    switch (s) {
    case fmi2Warning: return "logStatusWarning";
    case fmi2Discard: return "logStatusDiscard";
    case fmi2Error: return "logStatusError";
    case fmi2Fatal: return "logStatusFatal";
    default: return "logAll";
    }
}

/* a message to the importer's logger (never as its format) */
static void say(const Inst *I, fmi2Status status, const char *fmt, ...) {
    if (I == NULL || I->cb.logger == NULL) return;
    if (status == fmi2OK && !I->logging) return;
    char msg[2048];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    I->cb.logger(I->cb.componentEnvironment, I->name ? I->name : "", status, category(status),
                 "%s", msg);
}

/* Var.check for a Real: NULL if admissible, else the requirement (the range check is
 * cf_core.h's, fmi.c's too) */
static const char *requirement(const cf_var *v, double x) {
    const int range = cf_value_check(x, v->lo, v->hi, v->open_lo);
    if (range == CF_VALUE_NONFINITE) return "finite";
    if (v->type == T_INTEGER && x != floor(x)) return "an integer";
    if (range == CF_VALUE_BELOW) return v->lo_req;
    if (range == CF_VALUE_ABOVE) return v->hi_req;
    if (v->fix_req && x != v->fix) return v->fix_req;
    return NULL;
}

/* "NAME = VALUE is invalid: must be REQ" */
static void bad_text(const cf_var *v, double x, char *out, size_t n) {
    char r[40];
    py_repr(x, r, sizeof r);
    snprintf(out, n, "%s = %s is invalid: must be %s", v->name, r, requirement(v, x));
}

static int any_bad(const cf_core *c) {
    for (int i = 0; i < CF_N_VARS; i++)
        if (c->bad[i]) return 1;
    return 0;
}

/* the String parameters, method and scheme (by the role of variable i): the text held,
 * and the requirement of RollingBody's check (its words) */
static int is_scheme(int i) { return CF_VARS[i].role == R_SCHEME; }

static const char *string_text(const cf_core *c, int i) {
    return is_scheme(i) ? c->scheme_text : c->method_text;
}

static const char *string_choices(int i) {
    return is_scheme(i) ? "\"lobatto3c\" or \"sdirk2\"" : "\"full\" or \"quasistationary\"";
}

/* the message of the first bad value held that became bad after the order *last
 * (they are told in the order they became bad), *last moved to it; 0 when none is left */
static int next_bad(const cf_core *c, unsigned *last, char *one, size_t n) {
    int best = -1; /* few variables: a scan each */
    for (int i = 0; i < CF_N_VARS; i++)
        if (c->bad[i] > *last && (best < 0 || c->bad[i] < c->bad[best])) best = i;
    if (best < 0) return 0;
    *last = c->bad[best];
    if (CF_VARS[best].type == T_STRING)
        snprintf(one, n, "%s = '%s' is invalid: must be %s", CF_VARS[best].name,
                 string_text(c, best), string_choices(best));
    else
        bad_text(&CF_VARS[best], c->var[best], one, n);
    return 1;
}

/* the messages of the bad values held, in the order they became bad, joined by "; " */
static void bad_list(const Inst *I, char *out, size_t n) {
    size_t k = 0;
    unsigned last = 0;
    char one[256];
    out[0] = '\0';
    while (next_bad(&I->c, &last, one, sizeof one)) {
        int w = snprintf(out + k, n - k, "%s%s", k ? "; " : "", one);
        if (w < 0 || (size_t)w >= n - k) break;
        k += (size_t)w;
    }
}

/* ---- the model ------------------------------------------------------------------------ */
static void set_constants(cf_params *p, cf_body *b) {
    p->v_standstill = CF_V_STANDSTILL;
    p->v_scale_floor = CF_V_SCALE_FLOOR;
    p->z_algebraic = CF_Z_ALGEBRAIC;
    p->capacity_margin = CF_CAPACITY_MARGIN;
    p->solve_rtol = CF_SOLVE_RTOL;
    p->expand = CF_EXPAND;
    p->max_newton = CF_MAX_NEWTON;
    p->beta_full_slip = CF_BETA_FULL_SLIP;
    p->beta_series = CF_BETA_SERIES;
    p->fd_step = CF_FD_STEP;
    p->line_search_min = CF_LINE_SEARCH_MIN;
    p->contraction_max = CF_CONTRACTION_MAX;
    p->contraction_fast = CF_CONTRACTION_FAST;
    p->newton_iterations = CF_NEWTON_ITERATIONS;
    p->algebraic_key = CF_ALGEBRAIC_KEY;
    p->bracket = 1; /* a stage Newton cannot close: bracket and brentq, as Python does */
    p->max_expansions = CF_MAX_EXPANSIONS;
    p->gamma = CF_GAMMA;
    p->law = CF_TABLE ? LAW_TABLE : LAW_LAYER;
    p->saturation_width = CF_SAT_WIDTH;
    p->coef = p->ax1 = p->ax2 = p->ax3 = NULL; /* the table's: attach_table */
    p->strips = NULL;
    p->dyn_vy = p->dyn_spin = 0;
    p->rz = 0.0;
    p->Iz = 0.0;
    b->v_creep_floor = CF_V_CREEP_FLOOR;
    b->substep_slack = CF_SUBSTEP_SLACK;
    b->max_substeps = CF_MAX_SUBSTEPS;
}

/* the law at load P into p and b (its reported a2, p0) */
static void law_at_load(const cf_core *c, double P, cf_params *p, cf_body *b) {
    const double *v = c->val;
    if (CF_TABLE) { /* the table's coefficients do not depend on P (one load node) */
        cf_table_law(p, P, v[R_MU], CF_T_KFAC, CF_T_M, CF_T_AMIN, CF_T_A_LE_B, CF_T_ESTAR,
                     CF_T_G, CF_T_ONSET, &b->a2, &b->p0);
        return;
    }
    cf_layer_law(p, P, v[R_RX], v[R_RY], v[R_K1], v[R_K2], v[R_KB], v[R_KS], v[R_MU], &b->a2,
                 &b->p0);
}

/* the outputs of the struct into the variables */
static void publish(cf_core *c) {
    for (int i = 0; i < CF_N_VARS; i++)
        if (CF_VARS[i].kind == K_OUTPUT) c->var[i] = c->b.out[CF_VARS[i].role - R_OUT];
}

/* the FMU's outputs: a bit per index of cf_body.out (cf_first_nonfinite) */
static unsigned long served_mask(void) {
    unsigned long m = 0;
    for (int i = 0; i < CF_N_VARS; i++)
        if (CF_VARS[i].kind == K_OUTPUT) m |= 1ul << (CF_VARS[i].role - R_OUT);
    return m;
}

/* the name of the FMU's output out[i] */
static const char *out_name(int i) {
    for (int k = 0; k < CF_N_VARS; k++)
        if (CF_VARS[k].kind == K_OUTPUT && CF_VARS[k].role == R_OUT + i) return CF_VARS[k].name;
    return "?";
}

/* the name of the first of the FMU's outputs in out[] that is not finite (its value in
 * r), or NULL */
static const char *nonfinite(const double *out, char *r, size_t n) {
    const int i = cf_first_nonfinite(out, served_mask());
    if (i < 0) return NULL;
    py_repr(out[i], r, n);
    return out_name(i);
}

/* the spin grid g for the law at its load (p, b: a1, a2, p0 there) with the parameters
 * of c (mu, kb + ks), built unless it is already for these */
static const cf_strips *grid_at(spin_grid *g, const cf_core *c, const cf_params *law,
                                const cf_body *b) {
    const double *v = c->val;
    const double key[5] = {law->a1, b->a2, b->p0, v[R_MU], v[R_KB] + v[R_KS]};
    int same = 1;
    for (int k = 0; k < 5; k++) same = same && g->key[k] == key[k];
    if (!same) {
        cf_grid_build(&g->strips, g->x, g->y, g->dist, g->mid, g->cap, g->w, g->inside,
                      CF_SPIN_NX, CF_SPIN_NY, key[0], key[1], key[2], key[3], key[4], CF_TINY);
        memcpy(g->key, key, sizeof key);
    }
    return &g->strips;
}

/* LayerContact.forces for one input with spin phi != 0 on the spin grid g: rolling,
 * cf_layer_forces (the closed form plus the march with the spin less the march without
 * it); at standstill the same with the sliding field (cf_march_standstill), as numpy. */
static void spin_forces(const cf_params *p, const cf_strips *g, double vx, double vy,
                        double phi, double Vx, double T[3]) {
    if (Vx != 0.0) {
        cf_layer_forces(p, g, 1, &vx, &vy, &phi, &Vx, T); /* NaN for a non-finite input */
        return;
    }
    double with[3], without[3];
    forces(p, vx, vy, Vx, T);
    cf_march_standstill(g, vx, vy, phi, with);
    cf_march_standstill(g, vx, vy, 0.0, without);
    for (int k = 0; k < 3; k++) T[k] += with[k] - without[k];
}

/* ContactElement.evaluate: the law at the inputs' load and kinematics, rigid slip of
 * Eq. (3) at the contact centre (kinematics.rigid_slip), the forces (the closed form,
 * LayerContact._forces_scalar, or with a spin input Omega_z != 0 LayerContact.forces
 * by the strip march on the spin grid g, built here for the load) and
 * kinematics.contact_quantities; p and b hold the law at the load afterwards. The name
 * of a non-finite output, or NULL. */
static const char *contact_outputs(const cf_core *c, spin_grid *g, cf_params *p, cf_body *b,
                                   double out[N_OUT], char *r, size_t n) {
    const double *v = c->val;
    if (v[R_P] != p->P || v[R_MU] != p->mu) law_at_load(c, v[R_P], p, b); /* mu: tunable */
    const double Vx = v[R_VX], vx = Vx - v[R_OMEGA_Y] * v[R_RX], vy = v[R_VY];
    const double Omega_z = v[R_OMEGA_Z];
    double T[3], tab[4];
    const cf_strips *grid = NULL;
    if (CF_TABLE) {
        table_scalar(p, vx, vy, Omega_z, Vx, tab); /* CreepTable._scalar, spin included */
        T[0] = tab[0], T[1] = tab[1], T[2] = tab[2];
    } else if (CF_CONTACT_SPIN && Omega_z != 0.0 && g != NULL) {
        grid = grid_at(g, c, p, b);
        spin_forces(p, grid, vx, vy, Omega_z, Vx, T);
    } else {
        forces(p, vx, vy, Vx, T);
    }
    for (int i = 0; i < N_OUT; i++) out[i] = 0.0;
    out[O_TX] = T[0], out[O_TY] = T[1], out[O_MZ] = T[2];
    out[O_VX_SLIP] = vx, out[O_VY_SLIP] = vy;
    const double V = py_max(fabs(Vx), CF_V_CREEP_FLOOR);
    out[O_XI_X] = vx / V, out[O_XI_Y] = vy / V, out[O_XI_SP] = Omega_z / V;
    out[O_A1] = p->a1, out[O_A2] = b->a2, out[O_P0] = b->p0;
    out[O_ADHESION] = CF_TABLE ? tab[3]
                      : grid ? cf_spin_adhesion(grid, vx, vy, Vx, Omega_z, g->tau, g->slip,
                                                g->inside)
                             : adhesion_fraction(p, vx, vy, Vx);
    out[O_REGIME] = full_slip(p, vx, vy, Vx) ? 1.0 : 0.0;
    return nonfinite(out, r, n);
}

/* The initial state within the ranges of the body mode's steps (cf_body_out_check's
 * table, ranges.within_range(start=True)): beyond, every step would be discarded,
 * so the model cannot start; 0 with the reason logged, in within_range's words. Rx is
 * free to be small, so Omega_y0 = (Vx0 - vx0)/Rx can be beyond RATE_MAX. */
#define START_RANGE_WHY "Omega_y0 = (Vx0 - vx0)/Rx: the model cannot start there"
static int start_in_range(Inst *I, const double *out) {
    int which;
    if (cf_body_out_check(out, 0ul, &which) != CF_STEP_RANGE) return 1; /* 0: no finite check */
    const cf_ranged *q = &CF_RANGED[which];
    char rv[40];
    py_repr(out[q->i], rv, sizeof rv);
    say(I, fmi2Error, "cannot initialise the model: %s0 = %s is invalid: must be within abs "
        "<= %g (" START_RANGE_WHY ")", q->name, rv, q->bound);
    return 0;
}

/* the body's initial outputs: within range (start_in_range), then finite; 0 with the
 * reason logged */
static int start_ok(Inst *I, const double *out) {
    char r[40];
    if (!start_in_range(I, out)) return 0;
    const char *bad = nonfinite(out, r, sizeof r);
    if (bad) {
        say(I, fmi2Error, "cannot initialise the model: FloatingPointError: output %s = %s "
            "is not finite", bad, r);
        return 0;
    }
    return 1;
}

/* RigidBody (rigid_body.py): M, Rx, Iy > 0, the initial state */
static int build_rigid(Inst *I) {
    cf_core *c = &I->c;
    const double *v = c->val;
    static const int need[3] = {R_M, R_RX, R_IY};
    static const char *const names[3] = {"M", "Rx", "Iy"};
    for (int k = 0; k < 3; k++)
        if (!(v[need[k]] > 0.0)) {
            char r[40];
            py_repr(v[need[k]], r, sizeof r);
            say(I, fmi2Error, "cannot initialise the model: %s = %s is invalid: must be > 0",
                names[k], r);
            return 0;
        }
    double out[N_OUT] = {0};
    out[O_VX] = v[R_VX0];
    out[O_OMEGA_Y] = (v[R_VX0] - v[R_SLIP0]) / v[R_RX]; /* kinematics.spin_for_slip */
    if (!start_in_range(I, out)) return 0;
    c->rb_Vx = out[O_VX];
    c->rb_Omega_y = out[O_OMEGA_Y];
    c->b.out[O_VX] = c->rb_Vx;
    c->b.out[O_OMEGA_Y] = c->rb_Omega_y;
    c->built = 1;
    publish(c);
    return 1;
}

/* the spin grid at the law's load into p->strips */
static void ensure_grid(Inst *I, const cf_params *law, const cf_body *b, cf_params *p) {
    if (I->grid == NULL) return;
    p->strips = grid_at(I->grid, &I->c, law, b);
}

/* BodyModel / RollingBody set up from the parameters and inputs at the FMU's time;
 * 0 with the reasons logged (fmi2Error) where it cannot be */
static int build(Inst *I) {
    cf_core *c = &I->c;
    unsigned last = 0;
    char one[256];
    int held = 0;
    while (next_bad(c, &last, one, sizeof one)) { /* one message each, as slave.py */
        say(I, fmi2Error, "cannot initialise the model: %s", one);
        held = 1;
    }
    if (held) return 0;
    const double *v = c->val;
    char r[40];
    if (CF_MODE == MODE_RIGID) return build_rigid(I);
    /* LayerContact.__post_init__ beyond the declared ranges */
    if (!CF_TABLE && !(v[R_K1] + v[R_K2] > 0.0)) {
        py_repr(v[R_K1] + v[R_K2], r, sizeof r);
        say(I, fmi2Error, "cannot initialise the model: k1 + k2 = %s is invalid: must be > 0 "
            "(a Winkler layer carries the load)", r);
        return 0;
    }
    if (!CF_TABLE && !(v[R_KB] + v[R_KS] > 0.0)) {
        py_repr(v[R_KB] + v[R_KS], r, sizeof r);
        say(I, fmi2Error, "cannot initialise the model: kb + ks = %s is invalid: must be > 0 "
            "(tangential layer compliance)", r);
        return 0;
    }
    cf_params p;
    cf_body b;
    cf_state s;
    memset(&p, 0, sizeof p);
    memset(&b, 0, sizeof b);
    memset(&s, 0, sizeof s);
    set_constants(&p, &b);
    attach_table(I, &p);
    if (CF_MODE == MODE_CONTACT) {
        law_at_load(c, v[R_P], &p, &b);
        double out[N_OUT];
        const char *bad = contact_outputs(c, I->grid, &p, &b, out, r, sizeof r);
        if (bad) {
            say(I, fmi2Error, "cannot initialise the model: FloatingPointError: output %s = %s "
                "is not finite", bad, r);
            return 0;
        }
        c->p = p, c->b = b;
        memcpy(c->b.out, out, sizeof out);
        c->P_law = v[R_P];
        c->built = 1;
        c->dirty = 0;
        publish(c);
        return 1;
    }
    const double M = v[R_M], Rx = v[R_RX], Iy = v[R_IY];
    p.M = M, p.Rx = Rx;
    cf_body_inertia(&p, M, Rx, Iy);
    p.ry = v[R_VY_RATIO];
    p.quasistationary = c->method == 1;
    p.sdirk = c->scheme == 1;
    const double P = v[R_P];
    law_at_load(c, P, &p, &b);
    b.P = P, b.Fx_ex = v[R_FX_EX], b.My_ex = v[R_MY_EX], b.h_max = v[R_H_MAX];
    if (CF_VECTOR) {
        if (CF_DYN_SPIN && !(v[R_IZ] > 0.0)) {
            py_repr(v[R_IZ], r, sizeof r);
            say(I, fmi2Error, "cannot initialise the model: Iz = %s is invalid: must be > 0", r);
            return 0;
        }
        /* VectorKernel._path: the held ratios (0 where a rate is an unknown), Iz */
        p.ry = CF_DYN_VY ? 0.0 : v[R_VY_RATIO];
        p.rz = CF_DYN_SPIN ? 0.0 : v[R_SPIN_RATIO];
        p.dyn_vy = CF_DYN_VY, p.dyn_spin = CF_DYN_SPIN;
        p.Iz = CF_DYN_SPIN ? v[R_IZ] : 0.0;
        ensure_grid(I, &p, &b, &p);
        /* BodyState: y = (Vx0, Vx0 - Omega_y0 Rx, Vy0, Omega_z0), the held ratios, with
         * Omega_y0 = (Vx0 - vx0)/Rx (kinematics.spin_for_slip) */
        cf_vstate y;
        memset(&y, 0, sizeof y);
        y.Vx = v[R_VX0];
        y.vx = y.Vx - (v[R_VX0] - v[R_SLIP0]) / Rx * Rx;
        y.Vy = CF_DYN_VY ? v[R_VY0] : p.ry * y.Vx;
        y.Oz = CF_DYN_SPIN ? v[R_OMEGA_Z0] : p.rz * y.Vx;
        y.t = c->time;
        cf_initial_vforces(&p, &y);
        cf_vbody_outputs(&p, &y, &b, I->grid->tau, I->grid->slip, I->grid->inside);
        if (!start_ok(I, b.out)) return 0;
        c->p = p, c->b = b, c->vs = y;
        c->P_law = P;
        c->built = 1;
        publish(c);
        return 1;
    }
    /* BodyState: y = (Vx0, Vx0 - Omega_y0 Rx, ry Vx0, 0), the forces there */
    s.Vx = v[R_VX0];
    s.vx = s.Vx - (v[R_VX0] - v[R_SLIP0]) / Rx * Rx; /* Omega_y0 = (Vx0 - vx0)/Rx */
    s.t = c->time;
    cf_initial_forces(&p, &s);
    cf_body_outputs(&p, &s, &b);
    if (!start_ok(I, b.out)) return 0;
    c->p = p, c->b = b, c->s = s;
    c->P_law = P;
    c->built = 1;
    publish(c);
    return 1;
}

/* The words of a failed check of a step's outputs (cf_body_out_check's CF_STEP_RANGE,
 * which: the row of CF_RANGED, or CF_STEP_NONFINITE, which: the index into out), those
 * of ranges.within_range and slave._collect */
static void out_check_text(int why, int which, const double *out, char *t, size_t n) {
    char rv[40];
    if (why == CF_STEP_RANGE) {
        const cf_ranged *q = &CF_RANGED[which];
        py_repr(out[q->i], rv, sizeof rv);
        snprintf(t, n, "%s = %s is invalid: must be within abs <= %g (the loads drive the "
                 "body beyond it)", q->name, rv, q->bound);
    } else {
        py_repr(out[which], rv, sizeof rv);
        snprintf(t, n, "FloatingPointError: output %s = %s is not finite", out_name(which), rv);
    }
}

/* a step of the contact mode (the outputs at the inputs held) or of the rigid body
 * (Eqs. 8-9 under held inputs, exact: Vx += h (Fx_ex - Tx)/M, Omega_y += h (My_ex + Rx
 * Tx)/Iy), committed only when its outputs pass the checks of the body mode's
 * (cf_body_out_check: Vx, Omega_y within their ranges, then finite) */
static fmi2Status other_step(Inst *I, double t, double h) {
    cf_core *c = &I->c;
    char r[40], why_text[512] = "";
    if (CF_MODE == MODE_CONTACT) {
        cf_params p = c->p;
        cf_body b = c->b;
        double out[N_OUT];
        const char *bad = contact_outputs(c, I->grid, &p, &b, out, r, sizeof r);
        if (bad) {
            snprintf(why_text, sizeof why_text, "FloatingPointError: output %s = %s is not "
                     "finite", bad, r);
        } else {
            c->p = p, c->b = b, c->P_law = p.P, c->dirty = 0;
            memcpy(c->b.out, out, sizeof out);
        }
    } else {
        const double *v = c->val;
        const double Tx = v[R_TX];
        const double Vx = c->rb_Vx + h * (v[R_FX_EX] - Tx) / v[R_M];
        const double Oy = c->rb_Omega_y + h * (v[R_MY_EX] + v[R_RX] * Tx) / v[R_IY];
        double out[N_OUT] = {0.0};
        out[O_VX] = Vx, out[O_OMEGA_Y] = Oy;
        int which = 0;
        const int why = cf_body_out_check(out, I->served, &which);
        if (why != CF_OK) {
            out_check_text(why, which, out, why_text, sizeof why_text);
        } else {
            c->rb_Vx = Vx, c->rb_Omega_y = Oy;
            c->b.out[O_VX] = Vx, c->b.out[O_OMEGA_Y] = Oy;
        }
    }
    if (why_text[0]) {
        char rt[40], rh[40];
        py_repr(t, rt, sizeof rt);
        py_repr(h, rh, sizeof rh);
        say(I, fmi2Discard, "doStep at t = %s with h = %s discarded, state unchanged: %s", rt,
            rh, why_text);
        return fmi2Discard;
    }
    publish(c);
    c->time = t + h;
    return fmi2OK;
}

/* ContactSlave._refresh (direct feedthrough): the outputs for the inputs set, unless an
 * input is bad (then the last ones stay); an output that is not finite keeps them too,
 * with a logged error */
/* Contact mode's outputs for the current inputs; fmi2Error (the outputs kept are the
 * last good inputs', not to be used) where they cannot be had: slave._refresh */
static fmi2Status refresh(Inst *I) {
    cf_core *c = &I->c;
    for (int i = 0; i < CF_N_VARS; i++)
        if (c->bad[i] && CF_VARS[i].kind == K_INPUT) {
            char list[1536];
            bad_list(I, list, sizeof list);
            say(I, fmi2Error, "no outputs for the current inputs: %s", list);
            return fmi2Error;
        }
    cf_params p = c->p;
    cf_body b = c->b;
    double out[N_OUT];
    char r[40];
    const char *bad = contact_outputs(c, I->grid, &p, &b, out, r, sizeof r);
    if (bad) {
        say(I, fmi2Error, "no outputs for the current inputs: FloatingPointError: output "
            "%s = %s is not finite", bad, r);
        return fmi2Error;
    }
    c->p = p, c->b = b, c->P_law = p.P, c->dirty = 0;
    memcpy(c->b.out, out, sizeof out);
    publish(c);
    return fmi2OK;
}

/* BodyModel.step + the outputs, committed only when all is well */
static fmi2Status fmu_step(Inst *I, double t, double h) {
    cf_core *c = &I->c;
    /* t and h as Python writes them, formatted only for a message (a repr costs
     * microseconds: more than the step) */
    char rt[40], rh[40];
#define REPRS() (py_repr(t, rt, sizeof rt), py_repr(h, rh, sizeof rh))
    if (c->phase == PH_TERMINATED || !c->built) { /* slave._do_step's first refusal */
        char list[1536] = "";
        if (c->init_tried) bad_list(I, list, sizeof list); /* the values that stop it */
        REPRS();
        if (c->phase == PH_TERMINATED)
            say(I, fmi2Error, "doStep at t = %s refused: called after fmi2Terminate", rt);
        else
            say(I, fmi2Error, "doStep at t = %s refused: called before the model is initialised "
                "(fmi2ExitInitializationMode %s%s)", rt, c->init_tried ? "failed: " : "not called",
                c->init_tried ? (list[0] ? list : "see the messages above") : "");
        return fmi2Error;
    }
    if (!cf_step_size_ok(h)) {
        REPRS();
        say(I, fmi2Discard, "communicationStepSize = %s is invalid: must be > 0 and finite", rh);
        return fmi2Discard;
    }
    if (!cf_time_ok(t, c->time, CF_TIME_RTOL)) {
        char now[40];
        REPRS();
        py_repr(c->time, now, sizeof now);
        say(I, fmi2Discard, "currentCommunicationPoint = %s is invalid: must be the FMU's time "
            "%s", rt, now);
        return fmi2Discard;
    }
    if (c->next_bad && any_bad(c)) {
        char list[1536];
        bad_list(I, list, sizeof list);
        REPRS();
        say(I, fmi2Discard, "doStep at t = %s discarded, state unchanged: %s", rt, list);
        return fmi2Discard;
    }
    if (CF_MODE != MODE_BODY) return other_step(I, t, h);
    cf_params p = c->p;
    cf_body b = c->b;
    cf_state w = c->s;
    cf_vstate vw = c->vs;
    const double P = c->val[R_P];
    /* set_load: Eq. (34) at the new P; set_mu: the law at a tuned mu */
    if (P != c->P_law || c->val[R_MU] != p.mu) law_at_load(c, P, &p, &b);
    b.P = P, b.Fx_ex = c->val[R_FX_EX], b.My_ex = c->val[R_MY_EX];
    cf_vpath vector = {&vw, c->val[R_FY_EX], c->val[R_MZ_EX], NULL, NULL, NULL};
    if (CF_VECTOR) {
        ensure_grid(I, &p, &b, &p);
        vector.tau = I->grid->tau, vector.slip = I->grid->slip, vector.inside = I->grid->inside;
    }
    /* the step and its checks, those of the pythonfmu FMU's fast path (stepper.c), on
     * the copies p, b, w, vw */
    int capped = 0, which = 0;
    const int why = cf_body_check(&p, &w, CF_VECTOR ? &vector : NULL, &b, h, &capped,
                                  I->served, &which);
    if (why != CF_OK) {
        char rv[40], why_text[512];
        REPRS();
        if (why == CF_STEP_FX_LIMIT || why == CF_STEP_MY_LIMIT) { /* RollingBody._bounded */
            const int fx = why == CF_STEP_FX_LIMIT;
            const double cap = cf_load_cap(&p);
            py_repr(fx ? b.Fx_ex : b.My_ex, rv, sizeof rv);
            snprintf(why_text, sizeof why_text, "%s = %s is invalid: must be <= %g mu P%s = "
                     "%.6g %s in magnitude", fx ? "Fx_ex" : "My_ex", rv, CF_LOAD_LIMIT,
                     fx ? "" : " Rx", fx ? cap : cap * p.Rx, fx ? "N" : "N m");
        } else if (why == CF_STEP_RANGE || why == CF_STEP_NONFINITE) {
            out_check_text(why, which, b.out, why_text, sizeof why_text);
        } else if (why == CF_STEP_NO_SLIDING) {
            snprintf(why_text, sizeof why_text, "StageSolveError: eta = inf (Iy = 0) admits no "
                     "gross sliding: |A2 Fx_ex - A1 My_ex/Rx| = %.6g N reaches mu P = %.6g N",
                     fabs(target_x(&p, b.Fx_ex, b.My_ex)), p.mu * p.P);
        } else { /* CF_STEP_NO_ROOT: no other code reaches here (the law is at P, h > 0) */
            snprintf(why_text, sizeof why_text, "StageSolveError: no root: the stage residual "
                     "keeps its sign (loads beyond mu P?)");
        }
        say(I, fmi2Discard, "doStep at t = %s with h = %s discarded, state unchanged: %s", rt,
            rh, why_text);
        return fmi2Discard;
    }
    c->p = p, c->b = b, c->s = w, c->vs = vw, c->P_law = P;
    publish(c);
    c->time = t + h;
#undef REPRS
    const int n = b.max_substeps;
    if (capped && h / b.h_max > n)
        say(I, fmi2Warning, "communication step h = %g s exceeds %d internal steps of h_max = "
            "%g s: taken in %d steps of %g s", h, n, b.h_max, n, h / n);
    return fmi2OK;
}

/* the instance at its start values */
static void start_values(Inst *I) {
    cf_core *c = &I->c;
    memset(c, 0, sizeof *c);
    c->method = CF_METHOD_START;
    snprintf(c->method_text, METHOD_TEXT, "%s", METHOD_NAMES[CF_METHOD_START]);
    c->scheme = CF_SCHEME_START;
    snprintf(c->scheme_text, METHOD_TEXT, "%s", SCHEME_NAMES[CF_SCHEME_START]);
    for (int i = 0; i < CF_N_VARS; i++) {
        const cf_var *v = &CF_VARS[i];
        if (v->type == T_STRING) continue;
        c->var[i] = v->start;
        if (v->kind != K_OUTPUT && v->role < R_COUNT) c->val[v->role] = v->start;
    }
    c->phase = PH_INSTANTIATED;
}

/* ---- FMI 2.0 ----------------------------------------------------------------------------- */
#define INST(fn)                                                                         \
    Inst *I = (Inst *)c;                                                                 \
    if (I == NULL) return fmi2Error

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    INST(fmi2SetDebugLogging);
    (void)n, (void)cats;
    I->logging = on != fmi2False;
    return fmi2OK;
}

/* the table resource (fmu_build/native_fmu.py, table_bytes): "cfmuTBL1", n1, n2, n3
 * (u32), the count of doubles (u64), the axes and the patch coefficients (doubles), the
 * CRC-32 (zlib's) of all before it (u64); read from the resources folder (a file URI) at
 * instantiation into memory of the importer's; 0 with a logged reason */
static uint64_t crc32_of(const unsigned char *p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return (uint64_t)(c ^ 0xFFFFFFFFu);
}

static int load_table(Inst *I, const char *uri, const Inst *probe) {
    char path[4096];
    const char *s = uri ? uri : "";
    if (strncmp(s, "file://localhost/", 17) == 0) s += 16;
    else if (strncmp(s, "file:///", 8) == 0) s += 7;
    else if (strncmp(s, "file:/", 6) == 0) s += 5;
    size_t k = 0;
    for (; *s && k + 1 < sizeof path; s++) { /* percent-decoding */
        int hi, lo;
        if (s[0] == '%' && s[1] && s[2] && sscanf(s + 1, "%1x%1x", &hi, &lo) == 2) {
            path[k++] = (char)(hi * 16 + lo);
            s += 2;
        } else {
            path[k++] = *s;
        }
    }
#ifdef _WIN32
    if (k > 2 && path[0] == '/' && path[2] == ':') memmove(path, path + 1, k--); /* /C:/ */
#endif
    path[k] = '\0';
    const char *name = "/table.bin";
    if (k && path[k - 1] == '/') name++;
    if (k + strlen(name) + 1 > sizeof path) {
        say(probe, fmi2Error, "fmi2Instantiate: the resource path is too long");
        return 0;
    }
    strcat(path, name);
    const size_t n_data = (size_t)CF_T_N1 + CF_T_N2 + CF_T_N3 + CF_T_NCOEF;
    const size_t size = 8 + 12 + 8 + 8 * n_data + 8;
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        say(probe, fmi2Error, "fmi2Instantiate: the creep-force table %s cannot be opened", path);
        return 0;
    }
    unsigned char *buf = (unsigned char *)I->cb.allocateMemory(size + 1, 1);
    size_t got = buf ? fread(buf, 1, size + 1, f) : 0;
    fclose(f);
    const char *why = NULL;
    uint32_t n[3] = {0, 0, 0};
    uint64_t count = 0, sum = 0;
    if (buf == NULL) why = "out of memory";
    else if (got != size || memcmp(buf, "cfmuTBL1", 8) != 0) why = "not this FMU's table";
    else {
        memcpy(n, buf + 8, 12);
        memcpy(&count, buf + 20, 8);
        memcpy(&sum, buf + size - 8, 8);
        if (n[0] != CF_T_N1 || n[1] != CF_T_N2 || n[2] != CF_T_N3 || count != n_data)
            why = "its sizes are not this FMU's";
        else if (crc32_of(buf, size - 8) != sum) why = "damaged: its checksum does not match";
    }
    if (why) {
        say(probe, fmi2Error, "fmi2Instantiate: the creep-force table %s is refused: %s", path,
            why);
        if (buf) I->cb.freeMemory(buf);
        return 0;
    }
    I->table = (double *)I->cb.allocateMemory(n_data, sizeof(double));
    if (I->table) memcpy(I->table, buf + 28, 8 * n_data);
    I->cb.freeMemory(buf);
    if (I->table == NULL) say(probe, fmi2Error, "fmi2Instantiate: out of memory");
    return I->table != NULL;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean logging) {
    (void)resources, (void)visible;
    if (cb == NULL || cb->allocateMemory == NULL || cb->freeMemory == NULL) return NULL;
    Inst probe;
    memset(&probe, 0, sizeof probe);
    probe.cb = *cb;
    probe.name = (char *)(name ? name : "");
    if (type != fmi2CoSimulation) {
        say(&probe, fmi2Error, "fmi2Instantiate: this FMU is for co-simulation only");
        return NULL;
    }
    if (guid == NULL || strcmp(guid, CF_GUID) != 0) {
        say(&probe, fmi2Error, "fmi2Instantiate: GUID %s is not this FMU's (%s)",
            guid ? guid : "(null)", CF_GUID);
        return NULL;
    }
    Inst *I = (Inst *)cb->allocateMemory(1, sizeof(Inst));
    if (I == NULL) {
        say(&probe, fmi2Error, "fmi2Instantiate: out of memory");
        return NULL;
    }
    memset(I, 0, sizeof *I);
    I->cb = *cb;
    size_t len = strlen(probe.name) + 1;
    I->name = (char *)cb->allocateMemory(len, 1);
    if (I->name == NULL) {
        cb->freeMemory(I);
        say(&probe, fmi2Error, "fmi2Instantiate: out of memory");
        return NULL;
    }
    memcpy(I->name, probe.name, len);
    if (CF_TABLE && !load_table(I, resources, &probe)) {
        cb->freeMemory(I->name);
        cb->freeMemory(I);
        return NULL;
    }
    if (CF_GRID) {
        I->grid = (spin_grid *)cb->allocateMemory(1, sizeof(spin_grid));
        if (I->grid == NULL) {
            cb->freeMemory(I->name);
            cb->freeMemory(I);
            say(&probe, fmi2Error, "fmi2Instantiate: out of memory");
            return NULL;
        }
        for (int k = 0; k < 5; k++) I->grid->key[k] = NAN;
        I->grid->strips.ny = 0;
    }
    I->logging = logging != fmi2False;
    I->served = served_mask();
    start_values(I);
    return I;
}

void fmi2FreeInstance(fmi2Component c) {
    Inst *I = (Inst *)c;
    if (I == NULL) return;
    fmi2CallbackFreeMemory release = I->cb.freeMemory;
    for (size_t i = 0; i < I->cap_states; i++) /* the states the importer did not free */
        if (I->states[i]) release(I->states[i]);
    if (I->states) release(I->states);
    if (I->grid) release(I->grid);
    if (I->table) release(I->table);
    release(I->name);
    release(I);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stopDefined, fmi2Real stop) {
    INST(fmi2SetupExperiment);
    (void)tolDefined, (void)tol, (void)stopDefined, (void)stop;
    if (I->c.built) {
        say(I, fmi2Error, "fmi2SetupExperiment after initialisation is ignored");
        return fmi2Error;
    }
    if (isfinite(start)) {
        I->c.time = start;
        return fmi2OK;
    }
    char r[40];
    py_repr(start, r, sizeof r);
    say(I, fmi2Error, "startTime = %s is invalid: must be finite; using 0", r);
    return fmi2Error;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    INST(fmi2EnterInitializationMode);
    I->c.phase = PH_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    INST(fmi2ExitInitializationMode);
    I->c.init_tried = 1;
    if (!build(I)) { /* slave.exit_initialization_mode's refusal, its words */
        char list[1536];
        bad_list(I, list, sizeof list);
        say(I, fmi2Error, "exitInitializationMode: the model cannot start: %s",
            list[0] ? list : "see the messages above");
        return fmi2Error;
    }
    I->c.phase = PH_STEP;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    INST(fmi2Terminate);
    I->c.phase = PH_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    INST(fmi2Reset);
    start_values(I);
    return fmi2OK;
}

static int vr_ok(const Inst *I, fmi2ValueReference vr, int type, const char *fn) {
    if (vr < CF_N_VARS && CF_VARS[vr].type == type) return 1;
    say(I, fmi2Error, "%s: value reference %u is not a variable of this type", fn, (unsigned)vr);
    return 0;
}

/* A value that was refused is held, not to be used: fmi2Error (slave._get) */
static fmi2Status held_bad(const Inst *I, fmi2ValueReference vr) {
    if (!I->c.bad[vr]) return fmi2OK;
    char msg[256];
    bad_text(&CF_VARS[vr], I->c.var[vr], msg, sizeof msg);
    say(I, fmi2Error, "%s: %s (held until corrected)", CF_VARS[vr].name, msg);
    return fmi2Error;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    INST(fmi2GetReal);
    if (n > 0 && (vr == NULL || v == NULL)) return fmi2Error;
    fmi2Status status = fmi2OK;
    if (CF_MODE == MODE_CONTACT && I->c.dirty && I->c.built && n > 0) status = refresh(I);
    for (size_t i = 0; i < n; i++) {
        if (!vr_ok(I, vr[i], T_REAL, "fmi2GetReal")) return fmi2Error;
        v[i] = I->c.var[vr[i]];
        if (held_bad(I, vr[i]) != fmi2OK) status = fmi2Error;
    }
    return status;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer v[]) {
    INST(fmi2GetInteger);
    if (n > 0 && (vr == NULL || v == NULL)) return fmi2Error;
    fmi2Status status = fmi2OK;
    if (CF_MODE == MODE_CONTACT && I->c.dirty && I->c.built && n > 0) status = refresh(I);
    for (size_t i = 0; i < n; i++) {
        if (!vr_ok(I, vr[i], T_INTEGER, "fmi2GetInteger")) return fmi2Error;
        double x = I->c.var[vr[i]];
        v[i] = x > 0.5 ? 1 : 0; /* the only Integer: regime, 0 or 1 */
    }
    return status;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean v[]) {
    INST(fmi2GetBoolean);
    (void)v;
    if (n == 0) return fmi2OK;
    say(I, fmi2Error, "fmi2GetBoolean: this FMU has no Boolean variable (vr %u)",
        vr ? (unsigned)vr[0] : 0u);
    return fmi2Error;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         fmi2String v[]) {
    INST(fmi2GetString);
    if (n > 0 && (vr == NULL || v == NULL)) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        if (!vr_ok(I, vr[i], T_STRING, "fmi2GetString")) return fmi2Error;
        char *out = is_scheme((int)vr[i]) ? I->scheme_out : I->method_out;
        snprintf(out, METHOD_TEXT, "%s", string_text(&I->c, (int)vr[i]));
        v[i] = out;
    }
    return fmi2OK;
}

/* a parameter or input may be set now; else the refusal logged */
static int settable(Inst *I, int i, const char *value) {
    const cf_var *v = &CF_VARS[i];
    if (v->kind == K_OUTPUT) {
        say(I, fmi2Error, "%s is an output of this FMU: the value %s set is ignored", v->name,
            value);
        return 0;
    }
    if (v->kind == K_PARAMETER && I->c.built && v->role != R_MU) { /* mu is tunable */
        char now[80];
        if (v->type == T_STRING) snprintf(now, sizeof now, "'%s'", string_text(&I->c, i));
        else py_repr(I->c.var[i], now, sizeof now);
        say(I, fmi2Error, "%s is a fixed parameter and the model is initialised: %s = %s is "
            "ignored (%s stays %s)", v->name, v->name, value, v->name, now);
        return 0;
    }
    return 1;
}

static void mark(cf_core *c, int i, int bad) {
    if (!bad) c->bad[i] = 0;
    else if (!c->bad[i]) c->bad[i] = ++c->next_bad;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[]) {
    INST(fmi2SetReal);
    if (n > 0 && (vr == NULL || v == NULL)) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < n; k++) {
        if (!vr_ok(I, vr[k], T_REAL, "fmi2SetReal")) return fmi2Error;
        const int i = (int)vr[k];
        const cf_var *var = &CF_VARS[i];
        char r[40] = "";
        if (var->kind == K_OUTPUT || (var->kind == K_PARAMETER && I->c.built))
            py_repr(v[k], r, sizeof r); /* for the refusal's message */
        if (!settable(I, i, r)) {
            status = fmi2Error;
            continue;
        }
        cf_core *C = &I->c;
        C->var[i] = v[k];
        if (var->role < R_COUNT) C->val[var->role] = v[k];
        const int bad = requirement(var, v[k]) != NULL;
        mark(C, i, bad);
        /* an input, or the tunable mu: a force element's outputs follow */
        if (var->kind == K_INPUT || (var->role == R_MU && !bad)) C->dirty = 1;
        if (bad) { /* refused: fmi2Error, the value held (as the pythonfmu FMU) */
            char msg[256];
            bad_text(var, v[k], msg, sizeof msg);
            say(I, fmi2Error, "%s; doStep answers fmi2Discard until it is corrected", msg);
            status = fmi2Error;
        }
    }
    return status;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer v[]) {
    INST(fmi2SetInteger);
    (void)v;
    for (size_t k = 0; k < n; k++) {
        if (vr == NULL || !vr_ok(I, vr[k], T_INTEGER, "fmi2SetInteger")) return fmi2Error;
        char r[24];
        snprintf(r, sizeof r, "%d", (int)v[k]);
        settable(I, (int)vr[k], r); /* the only Integer is an output */
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean v[]) {
    INST(fmi2SetBoolean);
    (void)v;
    if (n == 0) return fmi2OK;
    say(I, fmi2Error, "fmi2SetBoolean: this FMU has no Boolean variable (vr %u)",
        vr ? (unsigned)vr[0] : 0u);
    return fmi2Error;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String v[]) {
    INST(fmi2SetString);
    if (n > 0 && (vr == NULL || v == NULL)) return fmi2Error;
    fmi2Status status = fmi2OK;
    for (size_t k = 0; k < n; k++) {
        if (!vr_ok(I, vr[k], T_STRING, "fmi2SetString")) return fmi2Error;
        const char *s = v[k] ? v[k] : "";
        char shown[METHOD_TEXT + 2];
        snprintf(shown, sizeof shown, "'%s'", s);
        if (!settable(I, (int)vr[k], shown)) {
            status = fmi2Error;
            continue;
        }
        cf_core *C = &I->c;
        const int i = (int)vr[k], scheme = is_scheme(i);
        char *text = scheme ? C->scheme_text : C->method_text;
        int *choice = scheme ? &C->scheme : &C->method;
        snprintf(text, METHOD_TEXT, "%s", s);
        *choice = -1;
        for (int m = 0; m < (scheme ? N_SCHEMES : N_METHODS); m++)
            if (strcmp(s, (scheme ? SCHEME_NAMES : METHOD_NAMES)[m]) == 0) *choice = m;
        /* RollingBody's check, at set-up in Python: here at once, the same words */
        mark(C, i, *choice < 0);
        if (*choice < 0) {
            say(I, fmi2Error, "%s = '%s' is invalid: must be %s; doStep answers fmi2Discard "
                "until it is corrected", CF_VARS[i].name, text, string_choices(i));
            status = fmi2Error;
        }
    }
    return status;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    INST(fmi2DoStep);
    (void)noSetPrior;
    return fmu_step(I, t, h);
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    INST(fmi2CancelStep);
    say(I, fmi2Error, "fmi2CancelStep: doStep runs synchronously; nothing to cancel");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    INST(fmi2GetStatus);
    (void)s, (void)v;
    say(I, fmi2Error, "fmi2GetStatus: doStep runs synchronously; no pending status");
    return fmi2Error;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    INST(fmi2GetRealStatus);
    if (s == fmi2LastSuccessfulTime && v != NULL) {
        *v = I->c.time;
        return fmi2OK;
    }
    say(I, fmi2Error, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is provided");
    return fmi2Error;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    INST(fmi2GetIntegerStatus);
    (void)s, (void)v;
    say(I, fmi2Error, "fmi2GetIntegerStatus: not provided");
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    INST(fmi2GetBooleanStatus);
    if (s == fmi2Terminated && v != NULL) {
        *v = fmi2False; /* the FMU never ends a simulation itself */
        return fmi2OK;
    }
    say(I, fmi2Error, "fmi2GetBooleanStatus: only fmi2Terminated is provided");
    return fmi2Error;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    INST(fmi2GetStringStatus);
    (void)s, (void)v;
    say(I, fmi2Error, "fmi2GetStringStatus: not provided");
    return fmi2Error;
}

/* d(Tx, Ty, Mz, vx, vy)/d(vx, vy, V) of the thin-layer law without spin at (vx, vy, V),
 * V != 0, analytic: T = mu P h(beta) e, Mz = sign(V) mu P a1 g(beta) e_y with
 * e = v/|v|, beta = |v| c/|V| (Eqs. 40-43 corrected; g = beta (h - 1)/2, docs/model.md),
 * so dT = mu P (h' dbeta e + h de), de = (I - e e^T) dv/|v|, dbeta = c e.dv/|V| -
 * beta dV/V; h/|v| = (h/beta)(c/|V|) from the series below BETA_SERIES. At v = 0 the
 * limits: dT = mu P h'(0) c dv/|V|, dMz = sign(V) mu P a1 g'(0) c dvy/|V|. */
static void law_jacobian(const cf_params *p, double vx, double vy, double V, double J[3][3]) {
    const double muP = p->mu * p->P, c = p->beta_per_creep, aV = fabs(V);
    const double sg = V > 0.0 ? 1.0 : -1.0, a1 = p->a1;
    const double s = hypot(vx, vy);
    if (s == 0.0) {
        const double d = muP * force_fraction_slope(p, 0.0) * c / aV;
        const double dg = -0.5; /* g'(0) = (h(0) - 1)/2 */
        double Z[3][3] = {{d, 0.0, 0.0}, {0.0, d, 0.0}, {0.0, sg * muP * a1 * dg * c / aV, 0.0}};
        memcpy(J, Z, sizeof Z);
        return;
    }
    const double ex = vx / s, ey = vy / s, beta = s * c / aV;
    double h = 1.0, dh = 0.0, dg = 0.0; /* g = beta (h - 1)/2 enters as g/|v| (g_s) */
    if (beta < p->beta_full_slip) {
        const double m = m_of(beta);
        h = py_min((2.0 / M_PI) * H_m(beta, m), 1.0);
        dh = slope_m(beta, m);
        dg = 0.5 * (h - 1.0) + 0.5 * beta * dh;
    }
    const double per_beta = beta < p->beta_series
        ? 16.0 / (3.0 * M_PI) - beta + 2.0 * beta * beta / (3.0 * M_PI)
        : h / beta;
    const double h_s = per_beta * c / aV;                       /* h/|v| */
    const double g_s = beta < p->beta_full_slip ? 0.5 * (h - 1.0) * c / aV : 0.0; /* g/|v| */
    const double db[3] = {c * ex / aV, c * ey / aV, -beta / V}; /* dbeta/d(vx, vy, V) */
    const double de[2][3] = {{ey * ey, -ex * ey, 0.0}, {-ex * ey, ex * ex, 0.0}}; /* |v| de */
    for (int k = 0; k < 3; k++) {
        J[0][k] = muP * ((dh != 0.0 ? dh * db[k] : 0.0) * ex + h_s * de[0][k]);
        J[1][k] = muP * ((dh != 0.0 ? dh * db[k] : 0.0) * ey + h_s * de[1][k]);
        J[2][k] = sg * muP * a1 * ((dg != 0.0 ? dg * db[k] : 0.0) * ey + g_s * de[1][k]);
    }
}

/* d(Tx, Ty, Mz)/d(vx, vy, V, phi) of what contact_outputs computes at the current
 * inputs (the law at their load in c->p), rolling (V != 0) on the thin-layer law: the
 * closed form's (law_jacobian) and, with a spin phi != 0, the march with the spin less
 * the march without it differentiated in forward mode (cf_march_jacobian), whose phi
 * column is the only one in phi. At phi = 0 the FMU computes the closed form alone, and
 * the phi column is the march's slope there (the correction's, which vanishes at 0;
 * marched only where the direction has a component in phi: need_phi). 0 where no
 * analytic form is had: standstill, the table. */
static int contact_jacobian(Inst *I, int need_phi, double J[3][4]) {
    const cf_core *c = &I->c;
    const double *v = c->val, Vx = v[R_VX];
    const double vx = Vx - v[R_OMEGA_Y] * v[R_RX], vy = v[R_VY], phi = v[R_OMEGA_Z];
    if (v[R_P] == 0.0) { /* lift-off: T = Mz = 0 at any kinematics, every derivative 0 */
        memset(J, 0, 3 * sizeof J[0]);
        return 1;
    }
    if (Vx == 0.0 || CF_TABLE) return 0;
    double L[3][3];
    law_jacobian(&c->p, vx, vy, Vx, L);
    for (int k = 0; k < 3; k++) {
        for (int j = 0; j < 3; j++) J[k][j] = L[k][j];
        J[k][3] = 0.0;
    }
    if (CF_CONTACT_SPIN && I->grid != NULL && (phi != 0.0 || need_phi)) {
        const cf_strips *g = grid_at(I->grid, c, &c->p, &c->b);
        double D[12], D0[12];
        cf_march_jacobian(g, vx, vy, Vx, phi, D);
        if (phi != 0.0) cf_march_jacobian(g, vx, vy, Vx, 0.0, D0);
        for (int k = 0; k < 3; k++) {
            J[k][3] = D[4 * k + 3];
            if (phi != 0.0)
                for (int j = 0; j < 3; j++) J[k][j] += D[4 * k + j] - D0[4 * k + j];
        }
    }
    return 1;
}

/* the output's row of d(outputs)/d(Vx, Vy, Omega_y, Omega_z) where it is analytic (J:
 * contact_jacobian's, have: whether there is one), else 0 */
static int analytic_row(const cf_core *c, int role, int have, const double J[3][4],
                        double row[4]) {
    const double Rx = c->val[R_RX];
    int k;
    switch (role - R_OUT) {
    case O_TX: k = 0; break;
    case O_TY: k = 1; break;
    case O_MZ: k = 2; break;
    case O_VX_SLIP: row[0] = 1.0, row[1] = 0.0, row[2] = -Rx, row[3] = 0.0; return 1;
    case O_VY_SLIP: row[0] = 0.0, row[1] = 1.0, row[2] = 0.0, row[3] = 0.0; return 1;
    default: return 0;
    }
    if (!have) return 0; /* standstill, or the table: differences */
    /* chain rule: vx = Vx - Omega_y Rx, vy = Vy, V = Vx, phi = Omega_z */
    row[0] = J[k][0] + J[k][2];
    row[1] = J[k][1];
    row[2] = -Rx * J[k][0];
    row[3] = J[k][3];
    return 1;
}

/* Contact mode: the directional derivative of the outputs (vUnknown) along the inputs
 * (vKnown, direction dvKnown) at the current inputs. Tx, Ty, Mz, vx, vy with respect
 * to Vx, Vy, Omega_y, Omega_z analytic (contact_jacobian); any other pair (P, the
 * creepages, the adhesion) by central differences of the outputs along the direction.
 * A derivative that is not finite (inputs near overflow) is an error, never served. */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference zr[], size_t nz,
                                        const fmi2ValueReference ur[], size_t nu,
                                        const fmi2Real du[], fmi2Real dz[]) {
    INST(fmi2GetDirectionalDerivative);
    if (CF_MODE != MODE_CONTACT) {
        say(I, fmi2Error, "fmi2GetDirectionalDerivative: provided by the contact mode only "
            "(providesDirectionalDerivative is false here)");
        return fmi2Error;
    }
    if ((nz && (zr == NULL || dz == NULL)) || (nu && (ur == NULL || du == NULL))) return fmi2Error;
    cf_core *C = &I->c;
    if (!C->built) {
        say(I, fmi2Error, "fmi2GetDirectionalDerivative: the model is not initialised");
        return fmi2Error;
    }
    if (C->next_bad && any_bad(C)) {
        say(I, fmi2Error, "fmi2GetDirectionalDerivative: an input is invalid (see setReal)");
        return fmi2Error;
    }
    if (C->dirty && refresh(I) != fmi2OK) return fmi2Error; /* logged there */
    int only_kin = 1; /* every known among (Vx, Vy, Omega_y, Omega_z) */
    double dir[4] = {0.0, 0.0, 0.0, 0.0};
    for (size_t j = 0; j < nu; j++) {
        if (ur[j] >= CF_N_VARS || CF_VARS[ur[j]].kind != K_INPUT || CF_VARS[ur[j]].type != T_REAL) {
            say(I, fmi2Error, "fmi2GetDirectionalDerivative: value reference %u is not a Real "
                "input", (unsigned)ur[j]);
            return fmi2Error;
        }
        const int role = CF_VARS[ur[j]].role;
        const int k = role == R_VX ? 0 : role == R_VY ? 1 : role == R_OMEGA_Y ? 2
                    : role == R_OMEGA_Z ? 3 : -1;
        if (k < 0) only_kin = 0;
        else dir[k] += du[j];
        if (!isfinite(du[j])) {
            say(I, fmi2Error, "fmi2GetDirectionalDerivative: a direction is not finite");
            return fmi2Error;
        }
    }
    /* central differences along the direction for what is not analytic */
    double plus[N_OUT], minus[N_OUT], eps = 0.0, J[3][4];
    int have_fd = 0, have_J = -1; /* -1: contact_jacobian not yet called */
    size_t i;
    for (i = 0; i < nz; i++) {
        if (zr[i] >= CF_N_VARS || CF_VARS[zr[i]].kind != K_OUTPUT ||
            CF_VARS[zr[i]].type != T_REAL) {
            say(I, fmi2Error, "fmi2GetDirectionalDerivative: value reference %u is not a Real "
                "output", (unsigned)zr[i]);
            return fmi2Error;
        }
        const int role = CF_VARS[zr[i]].role;
        double row[4];
        if (only_kin && have_J < 0 && role - R_OUT <= O_MZ && role - R_OUT >= O_TX)
            have_J = contact_jacobian(I, dir[3] != 0.0, J);
        if (only_kin && analytic_row(C, role, have_J > 0, J, row)) {
            dz[i] = row[0] * dir[0] + row[1] * dir[1] + row[2] * dir[2] + row[3] * dir[3];
            if (!isfinite(dz[i])) goto not_finite;
            continue;
        }
        if (!have_fd) {
            double size = 0.0, dn = 0.0;
            for (size_t j = 0; j < nu; j++) {
                size = fmax(size, fabs(C->val[CF_VARS[ur[j]].role]));
                dn = fmax(dn, fabs(du[j]));
            }
            eps = dn > 0.0 ? 1e-6 * fmax(size, 1e-3) / dn : 0.0;
            cf_core X = *C;
            char r[40];
            for (int sgn = 0; sgn < 2; sgn++) {
                for (size_t j = 0; j < nu; j++)
                    X.val[CF_VARS[ur[j]].role] = C->val[CF_VARS[ur[j]].role] +
                                                 (sgn ? -eps : eps) * du[j];
                cf_params p = C->p;
                cf_body b = C->b;
                if (contact_outputs(&X, I->grid, &p, &b, sgn ? minus : plus, r, sizeof r)) {
                    say(I, fmi2Error, "fmi2GetDirectionalDerivative: the outputs are not "
                        "finite next to the inputs");
                    return fmi2Error;
                }
            }
            have_fd = 1;
        }
        const int o = role - R_OUT;
        dz[i] = eps > 0.0 ? (plus[o] - minus[o]) / (2.0 * eps) : 0.0;
        if (!isfinite(dz[i])) goto not_finite;
    }
    return fmi2OK;
not_finite:
    say(I, fmi2Error, "fmi2GetDirectionalDerivative: the derivative of %s is not finite at "
        "the current inputs", CF_VARS[zr[i]].name);
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    INST(fmi2SetRealInputDerivatives);
    (void)vr, (void)n, (void)order, (void)v;
    say(I, fmi2Error, "fmi2SetRealInputDerivatives: inputs are held over a step "
        "(canInterpolateInputs is false)");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real v[]) {
    INST(fmi2GetRealOutputDerivatives);
    (void)vr, (void)n, (void)order, (void)v;
    say(I, fmi2Error, "fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder "
        "is 0)");
    return fmi2Error;
}

/* ---- FMU state ------------------------------------------------------------------------ */
/* a restored core made safe: what no legal state holds is reset (constants, pointers,
 * flags); values are whatever they were (a non-finite one only makes steps decline) */
static void sanitize(cf_core *c) {
    set_constants(&c->p, &c->b);
    if (c->method < -1 || c->method >= N_METHODS) c->method = -1;
    c->method_text[METHOD_TEXT - 1] = '\0';
    c->p.quasistationary = c->method == 1;
    if (c->scheme < -1 || c->scheme >= N_SCHEMES) c->scheme = -1;
    c->scheme_text[METHOD_TEXT - 1] = '\0';
    c->p.sdirk = c->scheme == 1;
    c->built = c->built != 0;
    c->dirty = c->dirty != 0;
    if (c->phase < PH_INSTANTIATED || c->phase > PH_TERMINATED) c->phase = PH_STEP;
    c->s.out_sliding = c->s.out_sliding != 0;
    c->s.sliding = c->s.sliding != 0;
    c->vs.out_sliding = c->vs.out_sliding != 0;
    c->vs.sliding = c->vs.sliding != 0;
    c->vs.jac_valid = c->vs.jac_valid != 0;
    c->p.ry = CF_DYN_VY ? 0.0 : c->val[R_VY_RATIO];
    c->p.rz = CF_DYN_SPIN ? 0.0 : c->val[R_SPIN_RATIO];
    c->p.dyn_vy = CF_VECTOR && CF_DYN_VY, c->p.dyn_spin = CF_VECTOR && CF_DYN_SPIN;
    c->p.Iz = CF_VECTOR && CF_DYN_SPIN ? c->val[R_IZ] : 0.0;
    unsigned top = 0;
    for (int i = 0; i < CF_N_VARS; i++) top = c->bad[i] > top ? c->bad[i] : top;
    c->next_bad = top;
}

/* The live states: FMI 2.0 forbids passing back a freed state or one of another
 * instance, but a pointer that is not a live state of this instance is refused
 * (fmi2Error, the pythonfmu FMU's words: pythonfmu_shim.c) instead of being read. The
 * pointer alone is looked up (a freed or foreign one cannot be dereferenced), in a hash
 * set: get, set and free stay O(1) with thousands of states held. */
static size_t slot_of(const Inst *I, const void *st) {
    uint64_t x = (uint64_t)(uintptr_t)st * 0x9E3779B97F4A7C15ull; /* Fibonacci hashing */
    return (size_t)(x >> 32) & (I->cap_states - 1);
}

static int live(const Inst *I, const void *st) {
    if (st == NULL || I->cap_states == 0) return 0;
    for (size_t i = slot_of(I, st);; i = (i + 1) & (I->cap_states - 1)) {
        if (I->states[i] == st) return 1;
        if (I->states[i] == NULL) return 0;
    }
}

static void put(Inst *I, cf_core *st) { /* room known to be there */
    size_t i = slot_of(I, st);
    while (I->states[i] != NULL) i = (i + 1) & (I->cap_states - 1);
    I->states[i] = st;
    I->n_states++;
}

/* a new state into the set (at most half full), 0 when out of memory */
static int keep(Inst *I, cf_core *st) {
    if (2 * (I->n_states + 1) > I->cap_states) {
        size_t cap = I->cap_states ? 2 * I->cap_states : 16, old = I->cap_states;
        cf_core **grown = (cf_core **)I->cb.allocateMemory(cap, sizeof *grown);
        if (grown == NULL) return 0;
        memset(grown, 0, cap * sizeof *grown);
        cf_core **was = I->states;
        I->states = grown, I->cap_states = cap, I->n_states = 0;
        for (size_t i = 0; i < old; i++)
            if (was[i]) put(I, was[i]);
        if (was) I->cb.freeMemory(was);
    }
    put(I, st);
    return 1;
}

static void forget(Inst *I, const void *st) { /* linear probing's backward-shift delete */
    const size_t mask = I->cap_states - 1;
    size_t i = slot_of(I, st);
    while (I->states[i] != st) i = (i + 1) & mask;
    for (size_t j = (i + 1) & mask; I->states[j] != NULL; j = (j + 1) & mask) {
        const size_t home = slot_of(I, I->states[j]);
        if (((j - home) & mask) >= ((j - i) & mask)) { /* its probe passes i: move it */
            I->states[i] = I->states[j];
            i = j;
        }
    }
    I->states[i] = NULL;
    I->n_states--;
}

static int live_or_refuse(const Inst *I, const void *st, const char *call) {
    if (live(I, st)) return 1;
    say(I, fmi2Error, "%s: %p is not an FMU state of this instance (never given, or freed)",
        call, st);
    return 0;
}

/* *state: NULL for a new state, else a live one to overwrite (FMI 2.0); NULL if out of
 * memory or refused (logged) */
static cf_core *state_to_fill(Inst *I, fmi2FMUstate *state, const char *call) {
    if (*state != NULL) return live_or_refuse(I, *state, call) ? (cf_core *)*state : NULL;
    cf_core *s = (cf_core *)I->cb.allocateMemory(1, sizeof(cf_core));
    if (s != NULL && keep(I, s)) return s;
    if (s != NULL) I->cb.freeMemory(s);
    say(I, fmi2Error, "%s: out of memory", call);
    return NULL;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    INST(fmi2GetFMUstate);
    if (state == NULL) {
        say(I, fmi2Error, "fmi2GetFMUstate: no place for the state given");
        return fmi2Error;
    }
    cf_core *s = state_to_fill(I, state, "fmi2GetFMUstate");
    if (s == NULL) return fmi2Error;
    *s = I->c;
    *state = s;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    INST(fmi2SetFMUstate);
    if (state == NULL) {
        say(I, fmi2Error, "fmi2SetFMUstate: no state given");
        return fmi2Error;
    }
    if (!live_or_refuse(I, state, "fmi2SetFMUstate")) return fmi2Error;
    I->c = *(const cf_core *)state;
    sanitize(&I->c);
    attach_table(I, &I->c.p);
    if (CF_VECTOR && I->c.built) ensure_grid(I, &I->c.p, &I->c.b, &I->c.p); /* its load's */
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    INST(fmi2FreeFMUstate);
    if (state == NULL) {
        say(I, fmi2Error, "fmi2FreeFMUstate: no state given");
        return fmi2Error;
    }
    if (*state == NULL) return fmi2OK; /* the standard: nothing to free */
    if (!live_or_refuse(I, *state, "fmi2FreeFMUstate")) return fmi2Error;
    forget(I, *state);
    I->cb.freeMemory(*state);
    *state = NULL;
    return fmi2OK;
}

/* serialized: MAGIC, format version (u32), GUID length (u32), GUID, payload length
 * (u64), payload (the cf_core), FNV-1a 64 of all that (u64); host byte order */
static const char MAGIC[8] = {'c', 'f', 'm', 'u', 'S', 'T', 'A', 'T'};
#define STATE_VERSION 1u

static uint64_t fnv1a(const unsigned char *p, size_t n) {
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

static size_t serialized_size(void) {
    return sizeof MAGIC + 4 + 4 + strlen(CF_GUID) + 8 + sizeof(cf_core) + 8;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    INST(fmi2SerializedFMUstateSize);
    if (size == NULL) {
        say(I, fmi2Error, "fmi2SerializedFMUstateSize: no place for the size given");
        return fmi2Error;
    }
    if (!live_or_refuse(I, state, "fmi2SerializedFMUstateSize")) return fmi2Error;
    *size = serialized_size();
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte out[],
                                 size_t size) {
    INST(fmi2SerializeFMUstate);
    if (!live_or_refuse(I, state, "fmi2SerializeFMUstate")) return fmi2Error;
    if (out == NULL || size < serialized_size()) {
        say(I, fmi2Error, "fmi2SerializeFMUstate: no buffer, or one of %zu bytes (%zu "
            "needed)", size, serialized_size());
        return fmi2Error;
    }
    unsigned char *p = (unsigned char *)out;
    const uint32_t version = STATE_VERSION, glen = (uint32_t)strlen(CF_GUID);
    const uint64_t plen = sizeof(cf_core);
    size_t k = 0;
    memcpy(p + k, MAGIC, sizeof MAGIC), k += sizeof MAGIC;
    memcpy(p + k, &version, 4), k += 4;
    memcpy(p + k, &glen, 4), k += 4;
    memcpy(p + k, CF_GUID, glen), k += glen;
    memcpy(p + k, &plen, 8), k += 8;
    memcpy(p + k, state, sizeof(cf_core)), k += sizeof(cf_core);
    const uint64_t sum = fnv1a(p, k);
    memcpy(p + k, &sum, 8);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte in[], size_t size,
                                   fmi2FMUstate *state) {
    INST(fmi2DeSerializeFMUstate);
    const unsigned char *p = (const unsigned char *)in;
    const char *why = NULL;
    uint32_t version = 0, glen = 0;
    uint64_t plen = 0, sum = 0;
    if (p == NULL || state == NULL) why = "no bytes";
    else if (size < sizeof MAGIC + 8 || memcmp(p, MAGIC, sizeof MAGIC) != 0)
        why = "not an FMU state of a contact_fmu native FMU";
    if (why == NULL) {
        memcpy(&version, p + 8, 4);
        memcpy(&glen, p + 12, 4);
        if (version != STATE_VERSION) why = "a format version this FMU does not read";
        else if (glen != strlen(CF_GUID) || size < 16 + (size_t)glen ||
                 memcmp(p + 16, CF_GUID, glen) != 0)
            why = "the state of another FMU (GUID differs)";
    }
    if (why == NULL) {
        if (size != serialized_size()) why = "damaged: its length is wrong";
        else {
            memcpy(&plen, p + 16 + glen, 8);
            memcpy(&sum, p + size - 8, 8);
            if (plen != sizeof(cf_core)) why = "damaged: its payload length is wrong";
            else if (fnv1a(p, size - 8) != sum) why = "damaged: its checksum does not match";
        }
    }
    if (why != NULL) {
        say(I, fmi2Error, "fmi2DeSerializeFMUstate: the bytes are refused: %s", why);
        return fmi2Error;
    }
    cf_core *s = state_to_fill(I, state, "fmi2DeSerializeFMUstate");
    if (s == NULL) return fmi2Error;
    memcpy(s, p + 16 + glen + 8, sizeof(cf_core));
    sanitize(s);
    *state = s;
    return fmi2OK;
}
