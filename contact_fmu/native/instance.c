/* The native FMU's instance layer (instance.h): one instance of contact_fmu's model
 * whatever FMI version calls it; fmi2.c is the FMI 2.0 front end on it, fmi3.c the FMI 3.0
 * one. The model is the
 * body mode on the compiled stepper (stepper.c), the contact mode (fmu/contact_model.py:
 * the thin-layer law, with a spin input by the strip march on the law's spin grid, and
 * its analytic directional derivatives) or the rigid_body mode (fmu/rigid_body.py), with
 * no Python anywhere (CF_MODE picks one); its numerics outside the kernel are model.c's.
 *
 * The body model is the one of fmu/body_model.py on its compiled paths: the thin-layer
 * law (layer.py; its contact ellipse and constants, Eqs. 33-34, derived here from the
 * parameters and the load P: cf_layer_law), Lobatto IIIC or SDIRK2 (the String parameter
 * scheme where the FMU offers both), methods "full" and "quasistationary"; vx the only
 * stage unknown (vy zero or held at a ratio, no spin: cf_advance; a held spin ratio:
 * the same step on the vector path's state, cf_advance_vector) or Vy and/or Omega_z as
 * unknowns too (Eqs. 10-11: cf_advance_vector, the
 * law's spin by the strip march on its grid, built here for each load: cf_grid_build).
 * The build refuses every other model (fmu_build/native_fmu.py). The variables, their
 * ranges, starts and the check messages come from contact_fmu/fmu/variables.py through
 * the generated cf_model.h; the constants the Python integrator uses travel in it too.
 *
 * Behaviour, the pythonfmu FMU's (contact_fmu/fmu/slave.py, docs/reliability.md), every
 * message a template of contact_fmu/fmu/messages.py (cf_messages.h's CF_MSG_*, the
 * pythonfmu FMU's words); in FMI 2.0's words (a status CF_STATUS_X is fmi2X):
 * - an inadmissible value (non-finite, out of its declared range) answers fmi2Error at
 *   its setter and is held, with a logged error naming the variable and the value;
 *   while it is held every doStep answers fmi2Discard with that message and changes
 *   nothing, getReal of it (and, in contact mode, of the outputs) fmi2Error; once
 *   corrected the instance steps normally;
 * - doStep before a successful exitInitializationMode or after fmi2Terminate:
 *   fmi2Error; with a step not in (0, inf) or not at the FMU's time (64 ulp of t):
 *   fmi2Discard; loads beyond integrator.LOAD_LIMIT mu P: fmi2Discard;
 * - exitInitializationMode before enterInitializationMode, terminate before the model
 *   is initialised: fmi2Error (the pythonfmu FMU's shim says the same);
 * - a step with no stage root (loads beyond mu P with an eta = inf body; a stage whose
 *   Newton iteration does not converge is bracketed and closed by brentq, as in Python)
 *   or with non-finite outputs: fmi2Discard, state unchanged;
 * - parameters are fixed once the model is set up: setting one then is refused
 *   (fmi2Error, the value kept); setting an output likewise. mu is tunable: the law is
 *   rebuilt at the next step (or, in contact mode, the next output read);
 * - a model that cannot be set up (bad parameters): fmi2Error at
 *   exitInitializationMode, with the reason.
 * Memory comes from the front end's callbacks; there is no mutable global: instances
 * are independent, also on several threads. The logger never gets user text as its
 * format. FMU state: the whole instance core (plain data), serialized with a format
 * version, the GUID, the length and a checksum; foreign or damaged bytes are refused,
 * and so is a state whose content no setter would have admitted (sanitize, state_ok).
 */
#include <limits.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cf_messages.h"
#include "instance.h"
#include "model.h"

#define N_METHODS 2
static const char *const METHOD_NAMES[N_METHODS] = {"full", "quasistationary"};
#define N_SCHEMES 2
static const char *const SCHEME_NAMES[N_SCHEMES] = {"lobatto3c", "sdirk2"}; /* integrator */

/* ---- the instance ------------------------------------------------------------------ */
typedef struct cf_inst Inst;
struct cf_inst {
    cf_callbacks cb;
    void *env;                    /* the front end's bytes (cf_instantiate), after this */
    const char *api;              /* "fmi2": the prefix of call names in messages */
    int v3;                       /* api "fmi3": FMI 3.0's call names (call_name) */
    char *name;
    int logging;
    cf_core c;
    char method_out[METHOD_TEXT]; /* what getString hands out */
    char scheme_out[METHOD_TEXT];
    spin_grid *grid;              /* CF_GRID only */
    field_scratch *field;         /* CF_TRANSIENT only */
    char field_out[2][FIELD_TEXT]; /* what getString hands out: field_file, field_times */
    double *table;                /* CF_TABLE: axes, each node's patches, spline (resource) */
    unsigned long served;         /* the FMU's outputs, a bit per index of cf_body.out */
    cf_core **states;             /* the live FMU states handed out: an open-addressing */
    size_t n_states, cap_states;  /* set of pointers (NULL: empty slot), cap a power of 2 */
};


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

static const char *category(cf_status s) {
    switch (s) {
    case CF_STATUS_WARNING: return "logStatusWarning";
    case CF_STATUS_DISCARD: return "logStatusDiscard";
    case CF_STATUS_ERROR: return "logStatusError";
    case CF_STATUS_FATAL: return "logStatusFatal";
    default: return "logAll";
    }
}

/* The FMI calls that messages name (cf_messages.h: CF_CALL_NAMES, from fmu/messages.py):
 * FMI 2.0's name and FMI 3.0's after the api prefix. */
typedef cf_call call_id;

static const char *call_name(const Inst *I, call_id k) { return CF_CALL_NAMES[k][I->v3]; }

/* a message to the importer's logger (never as its format): fmt is one of cf_messages.h's
 * CF_MSG_* (the wording of fmu/messages.py, the pythonfmu FMU's) */

static void vsay(const Inst *I, cf_status status, const char *fmt, va_list ap) {
    if (I == NULL || I->cb.log == NULL) return;
    if (status == CF_STATUS_OK && !I->logging) return;
    char msg[2048];
    vsnprintf(msg, sizeof msg, fmt, ap);
    I->cb.log(I->env, I->name ? I->name : "", (int)status, category(status), msg);
}

#if defined(__GNUC__) || defined(__clang__)
__attribute__((format(printf, 3, 4)))
#endif
static void say(const Inst *I, cf_status status, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsay(I, status, fmt, ap);
    va_end(ap);
}

void cf_log(const cf_inst *I, cf_status status, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsay(I, status, fmt, ap);
    va_end(ap);
}

/* a String value as Python's repr writes it, quoted: its buffer's size */
#define QUOTED ((FIELD_TEXT > METHOD_TEXT ? FIELD_TEXT : METHOD_TEXT) + 2)

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

/* a value as Python writes it: an Integer's whole value as an int, else repr */
static void value_text(const cf_var *v, double x, char *out, size_t n) {
    if (v->type == T_INTEGER && x == floor(x) && fabs(x) < 1e15) snprintf(out, n, "%.0f", x);
    else py_repr(x, out, n);
}

/* "NAME = VALUE is invalid: must be REQ" */
static void bad_text(const cf_var *v, double x, char *out, size_t n) {
    char r[40];
    value_text(v, x, r, sizeof r);
    snprintf(out, n, CF_MSG_INVALID, v->name, r, requirement(v, x));
}

static int any_bad(const cf_core *c) {
    for (int i = 0; i < CF_N_VARS; i++)
        if (c->bad[i]) return 1;
    return 0;
}

/* the String parameters, method and scheme (by the role of variable i), and phase
 * "transient"'s field_file and field_times: the text held, and the requirement (of
 * RollingBody's check, its words; the field's file: none, here) */
static int is_scheme(int i) { return CF_VARS[i].role == R_SCHEME; }
/* field_file, field_times: 0, 1; -1 for method and scheme */
static int field_string(int i) {
    const int role = CF_VARS[i].role;
    return role == R_FIELD_FILE || role == R_FIELD_TIMES ? role - R_FIELD_FILE : -1;
}

static const char *string_text(const cf_core *c, int i) {
    const int f = field_string(i);
    if (f >= 0) return c->field_text[f];
    return is_scheme(i) ? c->scheme_text : c->method_text;
}

/* what a String held must be where the FMU refuses it (RollingBody's words, and
 * body_transient.parse_times' for field_times), or NULL; buf (n bytes) holds the text of
 * a requirement that carries a number */
static const char *string_requirement(const cf_core *c, int i, char *buf, size_t n) {
    const int f = field_string(i);
    if (f >= 0) {
        const char *text = string_text(c, i);
        if (strlen(text) >= FIELD_TEXT - 1) /* set longer: cut */
            return snprintf(buf, n, CF_MSG_TEXT_TOO_LONG, FIELD_TEXT - 1), buf;
        if (f == 0) return NULL;
        double times[CF_FIELD_CAPTURES];
        const int k = cf_model_field_times(text, times);
        if (k == -3) snprintf(buf, n, CF_MSG_FIELD_TIMES_MANY, CF_FIELD_CAPTURES);
        return k == -1   ? CF_MSG_FIELD_TIMES_SYNTAX
               : k == -2 ? CF_MSG_FIELD_TIMES_FINITE
               : k == -3 ? buf
                         : NULL;
    }
    if ((is_scheme(i) ? c->scheme : c->method) >= 0) return NULL;
    return is_scheme(i) ? CF_MSG_SCHEME_CHOICES : CF_MSG_METHOD_CHOICES;
}

/* a String held that the FMU refuses */
static int string_bad(const cf_core *c, int i) {
    char buf[80];
    return string_requirement(c, i, buf, sizeof buf) != NULL;
}

/* the message of the first bad value held that became bad after the order *last
 * (they are told in the order they became bad), *last moved to it; 0 when none is left */
static int next_bad(const cf_core *c, unsigned *last, char *one, size_t n) {
    int best = -1; /* few variables: a scan each */
    for (int i = 0; i < CF_N_VARS; i++)
        if (c->bad[i] > *last && (best < 0 || c->bad[i] < c->bad[best])) best = i;
    if (best < 0) return 0;
    *last = c->bad[best];
    if (CF_VARS[best].type == T_STRING) {
        char q[QUOTED], buf[80];
        snprintf(q, sizeof q, "'%s'", string_text(c, best));
        snprintf(one, n, CF_MSG_INVALID, CF_VARS[best].name, q,
                 string_requirement(c, best, buf, sizeof buf));
    } else
        bad_text(&CF_VARS[best], c->var[best], one, n);
    return 1;
}

/* the messages of the bad values held, in the order they became bad, joined by "; " */
static void bad_list(const Inst *I, char *out, size_t n) {
    size_t k = 0;
    unsigned last = 0;
    char one[QUOTED + 256];
    out[0] = '\0';
    while (next_bad(&I->c, &last, one, sizeof one)) {
        int w = snprintf(out + k, n - k, "%s%s", k ? "; " : "", one);
        if (w < 0 || (size_t)w >= n - k) break;
        k += (size_t)w;
    }
}

/* ---- the model ------------------------------------------------------------------------ */

/* the outputs of the struct into the variables */
static void publish(cf_core *c) {
    for (int i = 0; i < CF_N_VARS; i++) {
        if (CF_VARS[i].kind != K_OUTPUT) continue;
        const int k = CF_VARS[i].role - R_OUT;
        c->var[i] = k < N_OUT ? c->b.out[k] : c->fs.fo[k - N_OUT];
    }
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

/* the contact mode's outputs at c's inputs (cf_model_contact_outputs): the name of the
 * first output served that is not finite (its value in r), or NULL */
static const char *contact_outputs(const Inst *I, const cf_core *c, cf_params *p, cf_body *b,
                                   double out[N_OUT], char *r, size_t n) {
    const int i = cf_model_contact_outputs(c, I->grid, p, b, out, I->served);
    if (i < 0) return NULL;
    py_repr(out[i], r, n);
    return out_name(i);
}


/* The initial state within the ranges of the body mode's steps (cf_body_out_check's
 * table, ranges.within_range(start=True)): beyond, every step would be discarded,
 * so the model cannot start; 0 with the reason logged, in within_range's words. Rx is
 * free to be small, so Omega_y0 = (Vx0 - vx0)/Rx can be beyond RATE_MAX. */
static int start_in_range(Inst *I, const double *out) {
    int which;
    if (cf_body_out_check(out, 0ul, &which) != CF_STEP_RANGE) return 1; /* 0: no finite check */
    const cf_ranged *q = &CF_RANGED[which];
    char rv[40], name[16], why[256];
    py_repr(out[q->i], rv, sizeof rv);
    snprintf(name, sizeof name, "%s0", q->name);
    snprintf(why, sizeof why, CF_MSG_OUT_OF_RANGE, name, rv, q->bound, CF_MSG_RANGE_START);
    say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
    return 0;
}

/* "cannot initialise the model: FloatingPointError: output NAME = R is not finite" */
static void start_not_finite(const Inst *I, const char *name, const char *r) {
    char why[256];
    snprintf(why, sizeof why, CF_MSG_OUTPUT_NOT_FINITE, name, r);
    say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
}

/* the body's initial outputs: within range (start_in_range), then finite; 0 with the
 * reason logged */
static int start_ok(Inst *I, const double *out) {
    char r[40];
    if (!start_in_range(I, out)) return 0;
    const char *bad = nonfinite(out, r, sizeof r);
    if (bad) {
        start_not_finite(I, bad, r);
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
            char r[40], why[256];
            py_repr(v[need[k]], r, sizeof r);
            snprintf(why, sizeof why, CF_MSG_NOT_POSITIVE, names[k], r);
            say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
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

/* TableLaw.__post_init__: a creep-force table with layers (kb + ks > 0) admits P = 0
 * (lift-off) or a load within its nodes' range (to spec.LOAD_RTOL), not one beyond,
 * where the load similarity it would extrapolate by does not hold: 1 with the refusal
 * in TableLaw's words in why, else 0 */
static int load_refused(double P, char *why, size_t n) {
    if (!CF_TABLE || !CF_T_LAYERED || P == 0.0 ||
        (CF_T_P_LO * (1.0 - CF_T_LOAD_RTOL) <= P && P <= CF_T_P_HI * (1.0 + CF_T_LOAD_RTOL)))
        return 0;
    char r[40];
    py_repr(P, r, sizeof r);
    snprintf(why, n, CF_MSG_TABLE_LOAD_RANGE, "P", r, CF_T_P_LO, CF_T_P_HI);
    return 1;
}

/* the spin grid at the law's load into p->strips */
static void ensure_grid(Inst *I, const cf_params *law, const cf_body *b, cf_params *p) {
    if (I->grid == NULL) return;
    p->strips = cf_model_grid(I->grid, &I->c, law, b);
}

/* body_transient._in_contact: the traction field needs a contact (P = 0.0 refused) */
static void liftoff_text(char *why, size_t n) { snprintf(why, n, CF_MSG_P_LIFTOFF, "P", "0.0"); }

/* the field's summary outputs served, finite (slave._collect), after cf_body_out_check:
 * the index into out (N_OUT_ALL) of the first that is not, or -1 */
static int field_nonfinite(const Inst *I, const double *out) {
    for (int k = N_OUT; k < N_OUT_ALL; k++)
        if ((I->served >> k & 1ul) && !isfinite(out[k])) return k;
    return -1;
}

/* FieldRecorder.capture_due at the state tr (time tr->t, the law law, lb): each requested
 * time reached (to TIME_RTOL 1e-9 of max(1, |t|)) and not yet captured, into c->cap[*n
 * ...), and the file written whole when one is; *n the captures then. 0, or -1 with the
 * write's failure in why (*n as it was: the captures are those of the state committed) */
static int capture_due(Inst *I, const cf_tstate *tr, const cf_params *law, const cf_body *lb,
                       int *n, char *why, size_t size) {
    cf_core *c = &I->c;
    double times[CF_FIELD_CAPTURES];
    if (!CF_TRANSIENT || c->field_text[0][0] == '\0') return 0; /* no file: no times */
    const int m = cf_model_field_times(c->field_text[1], times);
    const int before = *n;
    const double t = tr->t;
    while (*n < m && !(times[*n] > t + 1e-9 * fmax(1.0, fabs(t)))) {
        cf_capture *q = &c->cap[*n];
        q->wanted = times[*n], q->t = t, q->theta = tr->theta, q->direction = tr->direction;
        q->a1 = law->a1, q->a2 = lb->a2, q->p0 = lb->p0, q->mu = law->mu, q->P = law->P;
        memcpy(q->tau_x, tr->tau_x, sizeof q->tau_x);
        memcpy(q->tau_y, tr->tau_y, sizeof q->tau_y);
        memcpy(q->slip, tr->slip, sizeof q->slip);
        (*n)++;
    }
    if (*n == before) return 0;
    char err[256];
    if (cf_model_field_write(c->field_text[0], c->cap, *n, c->val[R_KB] + c->val[R_KS], tr,
                             I->field, err, sizeof err) != 0) {
        char q[QUOTED];
        snprintf(q, sizeof q, "'%s'", c->field_text[0]);
        snprintf(why, size, CF_MSG_FIELD_FILE, "field_file", q, err);
        *n = before;
        return -1;
    }
    return 0;
}

/* TransientBodyModel set up (body_transient.build, TransientRollingBody.__init__): the
 * field laid at the load and at rest (LayerField.__init__), the body at its initial state
 * (BodyState: y = (Vx0, Vx0 - Omega_y0 Rx, ry Vx0, rz Vx0), Omega_y0 = (Vx0 - vx0)/Rx),
 * the contact there (tau = 0: T = 0, not sliding), the outputs within range and finite */
static int build_transient(Inst *I, cf_params *p, cf_body *b) {
    cf_core *c = &I->c;
    const double *v = c->val;
    cf_tstate *fs = &I->field->trial;
    memset(fs, 0, sizeof *fs);
    cf_model_field_lay(p, b, fs);
    const double Vx0 = v[R_VX0], Omega_y0 = (Vx0 - v[R_SLIP0]) / p->Rx;
    fs->y[0] = Vx0;
    fs->y[1] = Vx0 - Omega_y0 * p->Rx;
    /* Lateral's held ratios (0 where none), or Vy0, Omega_z0 where an unknown */
    fs->y[2] = CF_DYN_VY ? v[R_VY0] : v[R_VY_RATIO] * Vx0;
    fs->y[3] = CF_DYN_SPIN ? v[R_OMEGA_Z0] : v[R_SPIN_RATIO] * Vx0;
    fs->t = c->time;
    cf_field f;
    cf_model_field(p, b, v[R_KB] + v[R_KS], fs, I->field, &f);
    double out[N_OUT_ALL];
    const int rc = cf_model_field_outputs(p, b, &f, fs, I->field, out);
    memcpy(b->out, out, sizeof b->out);
    if (!start_in_range(I, out)) return 0;
    char r[40];
    const char *bad = nonfinite(out, r, sizeof r);
    const int k = bad ? -1 : field_nonfinite(I, out);
    if (!bad && k >= 0) py_repr(out[k], r, sizeof r);
    if (bad || k >= 0) {
        start_not_finite(I, bad ? bad : out_name(k), r);
        return 0;
    }
    if (rc != CF_FIELD_OK) { /* the summary of a field at rest: no input reaches here */
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, CF_MSG_FIELD_SUMMARY);
        return 0;
    }
    int n = 0; /* the captures due at the start time (body_transient.build) */
    char why[FIELD_TEXT + 256];
    if (capture_due(I, fs, p, b, &n, why, sizeof why) != 0) {
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
        return 0;
    }
    c->n_captured = n;
    c->p = *p, c->b = *b, c->fs = *fs;
    c->P_law = p->P;
    c->built = 1;
    publish(c);
    return 1;
}

/* BodyModel / RollingBody set up from the parameters and inputs at the FMU's time;
 * 0 with the reasons logged (an error) where it cannot be */
static int build(Inst *I) {
    cf_core *c = &I->c;
    unsigned last = 0;
    char one[QUOTED + 256];
    int held = 0;
    while (next_bad(c, &last, one, sizeof one)) { /* one message each, as slave.py */
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, one);
        held = 1;
    }
    if (held) return 0;
    const double *v = c->val;
    char r[40], why[512];
    if (CF_MODE == MODE_RIGID) return build_rigid(I);
    if (CF_TRANSIENT && v[R_P] == 0.0) { /* body_transient.build's first check */
        liftoff_text(why, sizeof why);
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
        return 0;
    }
    /* LayerContact.__post_init__ beyond the declared ranges */
    if (!CF_TABLE && !(v[R_K1] + v[R_K2] > 0.0)) {
        py_repr(v[R_K1] + v[R_K2], r, sizeof r);
        snprintf(why, sizeof why, CF_MSG_WINKLER, "k1 + k2", r);
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
        return 0;
    }
    if (!CF_TABLE && !(v[R_KB] + v[R_KS] > 0.0)) {
        py_repr(v[R_KB] + v[R_KS], r, sizeof r);
        snprintf(why, sizeof why, CF_MSG_COMPLIANCE, "kb + ks", r);
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
        return 0;
    }
    cf_params p;
    cf_body b;
    cf_state s;
    memset(&p, 0, sizeof p);
    memset(&b, 0, sizeof b);
    memset(&s, 0, sizeof s);
    cf_model_constants(&p, &b);
    cf_model_attach_table(I->table, &p);
    if (load_refused(v[R_P], why, sizeof why)) { /* the law first, as make_law */
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
        return 0;
    }
    if (CF_MODE == MODE_CONTACT) {
        cf_model_law_at_load(c, v[R_P], &p, &b);
        double out[N_OUT];
        const char *bad = contact_outputs(I, c, &p, &b, out, r, sizeof r);
        if (bad) {
            start_not_finite(I, bad, r);
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
    if (CF_VECTOR && CF_DYN_SPIN && !(v[R_IZ] > 0.0)) { /* dynamics.Body's checks */
        py_repr(v[R_IZ], r, sizeof r);
        snprintf(why, sizeof why, CF_MSG_NOT_POSITIVE, "Iz", r);
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
        return 0;
    }
    /* A1, A2 (Eq. 23) divide by M Rx^2 + Iy: it must neither underflow to 0 nor overflow
     * (each value alone admissible, e.g. Rx = 1e-200 with Iy = 0) */
    const double MR2 = M * pow(Rx, 2.0), inertia = MR2 + Iy;
    if (!(0.0 < MR2 && MR2 < INFINITY && inertia < INFINITY)) {
        char rM[40], rR[40], rI[40];
        py_repr(inertia, r, sizeof r);
        py_repr(M, rM, sizeof rM);
        py_repr(Rx, rR, sizeof rR);
        py_repr(Iy, rI, sizeof rI);
        snprintf(why, sizeof why, CF_MSG_INERTIA, "M Rx^2 + Iy", r, rM, rR, rI);
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_INITIALISE, why);
        return 0;
    }
    p.M = M, p.Rx = Rx;
    cf_body_inertia(&p, M, Rx, Iy);
    p.ry = v[R_VY_RATIO];
    p.quasistationary = c->method == 1;
    p.sdirk = c->scheme == 1;
    const double P = v[R_P];
    cf_model_law_at_load(c, P, &p, &b);
    b.P = P, b.Fx_ex = v[R_FX_EX], b.My_ex = v[R_MY_EX], b.h_max = v[R_H_MAX];
    if (CF_TRANSIENT) return build_transient(I, &p, &b);
    if (CF_VECTOR) {
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
        snprintf(t, n, CF_MSG_OUT_OF_RANGE, q->name, rv, q->bound, CF_MSG_RANGE_STEP);
    } else {
        py_repr(out[which], rv, sizeof rv);
        snprintf(t, n, CF_MSG_OUTPUT_NOT_FINITE, out_name(which), rv);
    }
}

/* a step of the contact mode (the outputs at the inputs held) or of the rigid body
 * (Eqs. 8-9 under held inputs: cf_model_rigid_step), committed only when its outputs
 * pass the checks of the body mode's
 * (cf_body_out_check: Vx, Omega_y within their ranges, then finite) */
static cf_status other_step(Inst *I, double t, double h) {
    cf_core *c = &I->c;
    char r[40], why_text[512] = "";
    if (CF_MODE == MODE_CONTACT) {
        cf_params p = c->p;
        cf_body b = c->b;
        double out[N_OUT];
        const int refused = load_refused(c->val[R_P], why_text, sizeof why_text);
        const char *bad = refused ? NULL : contact_outputs(I, c, &p, &b, out, r, sizeof r);
        if (bad) {
            snprintf(why_text, sizeof why_text, CF_MSG_OUTPUT_NOT_FINITE, bad, r);
        } else if (!refused) {
            c->p = p, c->b = b, c->P_law = p.P, c->dirty = 0;
            memcpy(c->b.out, out, sizeof out);
        }
    } else {
        double out[N_OUT];
        cf_model_rigid_step(c, h, out);
        const double Vx = out[O_VX], Oy = out[O_OMEGA_Y];
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
        say(I, CF_STATUS_DISCARD, CF_MSG_STEP_DISCARDED, rt, rh, why_text);
        return CF_STATUS_DISCARD;
    }
    publish(c);
    c->time = t + h;
    return CF_STATUS_OK;
}

/* ContactSlave._refresh (direct feedthrough): the contact mode's outputs for the inputs
 * set; an error (the outputs kept are the last good inputs', not to be used) where they
 * cannot be had: an input held bad, an output that is not finite */
static cf_status refresh(Inst *I) {
    cf_core *c = &I->c;
    for (int i = 0; i < CF_N_VARS; i++)
        if (c->bad[i] && CF_VARS[i].kind == K_INPUT) {
            char list[1536];
            bad_list(I, list, sizeof list);
            say(I, CF_STATUS_ERROR, CF_MSG_NO_OUTPUTS, list);
            return CF_STATUS_ERROR;
        }
    cf_params p = c->p;
    cf_body b = c->b;
    double out[N_OUT];
    char r[40], why[512];
    if (load_refused(c->val[R_P], why, sizeof why)) {
        say(I, CF_STATUS_ERROR, CF_MSG_NO_OUTPUTS, why);
        return CF_STATUS_ERROR;
    }
    const char *bad = contact_outputs(I, c, &p, &b, out, r, sizeof r);
    if (bad) {
        snprintf(why, sizeof why, CF_MSG_OUTPUT_NOT_FINITE, bad, r);
        say(I, CF_STATUS_ERROR, CF_MSG_NO_OUTPUTS, why);
        return CF_STATUS_ERROR;
    }
    c->p = p, c->b = b, c->P_law = p.P, c->dirty = 0;
    memcpy(c->b.out, out, sizeof out);
    publish(c);
    return CF_STATUS_OK;
}

/* Python's a // b for doubles a >= 0, b > 0 (float_floor_div: the quotient of a - fmod(a,
 * b), floored, rounded up where it falls short by more than one half) */
static double py_floordiv(double a, double b) {
    const double mod = fmod(a, b), div = (a - mod) / b;
    double q = floor(div);
    if (div - q > 0.5) q += 1.0;
    return q;
}

/* TransientBodyModel.step + the outputs, committed only when all is well: the load
 * (set_load: the ellipse follows P, Eq. 34, the field is kept; the lattice and strips
 * laid at the set-up load stay while the contact fits them, and a load whose contact
 * outgrows them, which the Python field extends, is refused: the field here has the
 * scene's fixed size), the budget (an internal step costs nx ny WORK_PER_CELL), the
 * internal steps (max(ceil(h/h_max), the steps of cells_per_step cells at the present
 * speed), at most the budget's), TransientRollingBody.advance (cf_field_advance) on a
 * trial copy of the state, the outputs' checks. The words of the pythonfmu FMU. */
static cf_status transient_step(Inst *I, double t, double h) {
    cf_core *c = &I->c;
    field_scratch *sc = I->field;
    const double *v = c->val;
    char why[FIELD_TEXT + 640] = "", r[40];
    int n_captured = c->n_captured;
    cf_params p = c->p;
    cf_body b = c->b;
    const double P = v[R_P];
    const double work = (double)CF_FIELD_NX * CF_FIELD_NY * CF_WORK_PER_CELL;
    const double cap = floor(v[R_MAX_WORK] / work); /* max_work <= 1e9: fits an int */
    double needed = 1.0;
    double out[N_OUT_ALL];
    int n = 1;
    if (P == 0.0) {
        liftoff_text(why, sizeof why);
    } else if (cap < 1.0) {
        py_repr(v[R_MAX_WORK], r, sizeof r);
        snprintf(why, sizeof why, CF_MSG_MAX_WORK_FIELD, "max_work", r, work, CF_FIELD_NX,
                 CF_FIELD_NY);
    } else {
        const cf_tstate *fs = &c->fs;
        if (P != c->P_law || v[R_MU] != p.mu) cf_model_law_at_load(c, P, &p, &b);
        /* LayerField.set_load's growth: columns where a1 passes X, strips where a2 passes Y */
        if (P != c->P_law && (ceil((p.a1 - fs->X) / fs->dx - 1e-12) > 0.0 || b.a2 > fs->Y)) {
            py_repr(P, r, sizeof r);
            snprintf(why, sizeof why, CF_MSG_FIELD_OUTGROWN, r, p.a1, b.a2, fs->X, fs->Y,
                     CF_FIELD_NX, CF_FIELD_NY);
        }
    }
    if (!why[0]) {
        /* TransientBodyModel.needed_steps: body_model.substeps (uncapped) and
         * substeps_for(h, cells_per_step) at the state's Vx; inf where h/h_max overflows */
        const double by_h = fmax(ceil(h / v[R_H_MAX] * (1.0 - CF_SUBSTEP_SLACK)), 1.0);
        const double by_cells = fmax(1.0, ceil(h * fabs(c->fs.y[0]) /
                                               (v[R_CELLS_PER_STEP] * c->fs.dx) - 1e-9));
        needed = fmax(by_h, by_cells);
        n = needed > cap ? (int)cap : (int)needed;
        cf_tstate *tr = &sc->trial;
        *tr = c->fs;
        cf_field f;
        cf_model_field(&p, &b, v[R_KB] + v[R_KS], tr, sc, &f);
        /* with Vy or Omega_z as unknowns the field's evaluations count against
         * max_work (EvalBudget: max(1, max_work // (nx ny WORK_PER_CELL_EVAL))) */
        const double eval_work = (double)CF_FIELD_NX * CF_FIELD_NY * CF_WORK_PER_CELL_EVAL;
        const double evals = fmin(fmax(py_floordiv(v[R_MAX_WORK], eval_work), 1.0), INT_MAX);
        const cf_field_body fb = {p.M, p.Rx, p.A1, p.A2, p.m_slip, v[R_VY_RATIO],
                                  v[R_SPIN_RATIO], p.creep_full_slip, CF_GAMMA,
                                  CF_FIELD_A21, CF_SOLVE_RTOL, CF_V_SCALE_FLOOR,
                                  CF_FIELD_MAX_ITERATIONS, CF_DYN_VY, CF_DYN_SPIN,
                                  CF_DYN_SPIN ? v[R_IZ] : 0.0, p.a1,
                                  CF_DYN_VY || CF_DYN_SPIN ? (int)evals : 0};
        cf_field_body_state st;
        memcpy(st.y, tr->y, sizeof st.y);
        st.t = tr->t;
        memcpy(st.impulse, tr->impulse, sizeof st.impulse);
        st.theta = tr->theta, st.direction = tr->direction;
        st.tau_x = tr->tau_x, st.tau_y = tr->tau_y, st.slip = tr->slip;
        memcpy(st.T, tr->T, sizeof st.T);
        st.sliding = tr->sliding;
        st.work = sc->work, st.bytes = sc->bytes;
        const double loads[4] = {v[R_FX_EX], v[R_FY_EX], v[R_MY_EX], v[R_MZ_EX]};
        int rc = cf_field_advance(&f, &fb, &st, h, loads, n);
        if (rc == CF_FIELD_OK) {
            memcpy(tr->y, st.y, sizeof st.y);
            tr->t = st.t;
            memcpy(tr->impulse, st.impulse, sizeof st.impulse);
            tr->theta = st.theta, tr->direction = st.direction;
            memcpy(tr->T, st.T, sizeof st.T);
            tr->sliding = st.sliding != 0;
            rc = cf_model_field_outputs(&p, &b, &f, tr, sc, out);
        }
        int which = 0, k = -1;
        const int check = rc == CF_FIELD_OK ? cf_body_out_check(out, I->served, &which) : CF_OK;
        if (rc == CF_FIELD_OK && check == CF_OK) k = field_nonfinite(I, out);
        if (rc == CF_FIELD_BUDGET) { /* WorkBudgetError, as BodyModel.step words it */
            snprintf(why, sizeof why, CF_MSG_WORK_BUDGET_MAX, fb.eval_limit, v[R_MAX_WORK],
                     eval_work);
        } else if (rc == CF_FIELD_NO_ROOT) { /* TransientRollingBody._solve_scalar's words */
            snprintf(why, sizeof why, CF_MSG_FIELD_NO_ROOT,
                     p.A2 * v[R_FX_EX] - p.A1 * v[R_MY_EX] / p.Rx, p.mu * p.P);
        } else if (rc == CF_FIELD_RANGE) {
            snprintf(why, sizeof why, CF_MSG_FIELD_SHIFT, CF_FIELD_SHIFT_MAX);
        } else if (rc != CF_FIELD_OK) {
            snprintf(why, sizeof why, CF_MSG_FIELD_NOT_FINITE);
        } else if (check != CF_OK) {
            out_check_text(check, which, out, why, sizeof why);
        } else if (k >= 0) {
            py_repr(out[k], r, sizeof r);
            snprintf(why, sizeof why, CF_MSG_OUTPUT_NOT_FINITE, out_name(k), r);
        } else {
            capture_due(I, tr, &p, &b, &n_captured, why, sizeof why); /* why: its failure */
        }
    }
    if (why[0]) {
        char rt[40], rh[40];
        py_repr(t, rt, sizeof rt);
        py_repr(h, rh, sizeof rh);
        say(I, CF_STATUS_DISCARD, CF_MSG_STEP_DISCARDED, rt, rh, why);
        return CF_STATUS_DISCARD;
    }
    memcpy(b.out, out, sizeof b.out);
    c->p = p, c->b = b, c->fs = sc->trial, c->P_law = P, c->n_captured = n_captured;
    publish(c);
    c->time = t + h;
    if (needed > cap) { /* TransientBodyModel.step's cap_note */
        say(I, CF_STATUS_WARNING, CF_MSG_CAP_NOTE_FIELD, h, v[R_H_MAX], v[R_CELLS_PER_STEP],
            v[R_MAX_WORK], work, n, h / n);
        return CF_STATUS_WARNING;
    }
    return CF_STATUS_OK;
}

/* BodyModel.step + the outputs, committed only when all is well */
static cf_status fmu_step(Inst *I, double t, double h) {
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
            say(I, CF_STATUS_ERROR, CF_MSG_STEP_AFTER_TERMINATE, rt, I->api,
                call_name(I, CF_CALL_TERMINATE));
        else if (c->init_tried)
            say(I, CF_STATUS_ERROR, CF_MSG_STEP_AFTER_FAILED_INIT, rt, I->api,
                list[0] ? list : CF_MSG_SEE_ABOVE);
        else
            say(I, CF_STATUS_ERROR, CF_MSG_STEP_BEFORE_INIT, rt, I->api);
        return CF_STATUS_ERROR;
    }
    if (!cf_step_size_ok(h)) {
        REPRS();
        say(I, CF_STATUS_DISCARD, CF_MSG_STEP_SIZE, rh);
        return CF_STATUS_DISCARD;
    }
    if (!cf_time_ok(t, c->time, CF_TIME_RTOL)) {
        char now[40];
        REPRS();
        py_repr(c->time, now, sizeof now);
        say(I, CF_STATUS_DISCARD, CF_MSG_STEP_TIME, rt, now);
        return CF_STATUS_DISCARD;
    }
    if (c->next_bad && any_bad(c)) {
        char list[1536];
        bad_list(I, list, sizeof list);
        REPRS();
        say(I, CF_STATUS_DISCARD, CF_MSG_STEP_HELD, rt, list);
        return CF_STATUS_DISCARD;
    }
    if (CF_MODE != MODE_BODY) return other_step(I, t, h);
    if (CF_TRANSIENT) return transient_step(I, t, h);
    cf_params p = c->p;
    cf_body b = c->b;
    cf_state w = c->s;
    cf_vstate vw = c->vs;
    const double P = c->val[R_P];
    char refusal[512];
    if (P != c->P_law && load_refused(P, refusal, sizeof refusal)) { /* set_load's */
        REPRS();
        say(I, CF_STATUS_DISCARD, CF_MSG_STEP_DISCARDED, rt, rh, refusal);
        return CF_STATUS_DISCARD;
    }
    /* set_load: Eq. (34) at the new P; set_mu: the law at a tuned mu */
    if (P != c->P_law || c->val[R_MU] != p.mu) cf_model_law_at_load(c, P, &p, &b);
    b.P = P, b.Fx_ex = c->val[R_FX_EX], b.My_ex = c->val[R_MY_EX];
    /* the budget max_work in internal steps of this path (body_model.step_cap): at
     * least 1 (max_work <= 1e9: the cap fits an int) */
    const double work =
        CF_DYN_VY || CF_DYN_SPIN || (CF_HELD_SPIN && !CF_TABLE) ? CF_WORK_VECTOR : CF_WORK_SCALAR;
    const double steps = floor(c->val[R_MAX_WORK] / work);
    b.max_substeps = steps >= 1.0 ? (int)fmin(steps, (double)INT_MAX) : 1;
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
            snprintf(why_text, sizeof why_text, fx ? CF_MSG_LOAD_LIMIT_FX : CF_MSG_LOAD_LIMIT_MY,
                     fx ? "Fx_ex" : "My_ex", rv, CF_LOAD_LIMIT, fx ? cap : cap * p.Rx);
        } else if (why == CF_STEP_RANGE || why == CF_STEP_NONFINITE) {
            out_check_text(why, which, b.out, why_text, sizeof why_text);
        } else if (why == CF_STEP_NO_SLIDING) {
            snprintf(why_text, sizeof why_text, CF_MSG_NO_GROSS_SLIDING,
                     fabs(cf_target_x(&p, b.Fx_ex, b.My_ex)), p.mu * p.P);
        } else { /* CF_STEP_NO_ROOT: no other code reaches here (the law is at P, h > 0) */
            snprintf(why_text, sizeof why_text, CF_MSG_NO_ROOT);
        }
        say(I, CF_STATUS_DISCARD, CF_MSG_STEP_DISCARDED, rt, rh, why_text);
        return CF_STATUS_DISCARD;
    }
    c->p = p, c->b = b, c->s = w, c->vs = vw, c->P_law = P;
    publish(c);
    c->time = t + h;
#undef REPRS
    const int n = b.max_substeps;
    if (capped && h / b.h_max > n) { /* BodyModel.cap_note */
        say(I, CF_STATUS_WARNING, CF_MSG_CAP_NOTE_BODY, h, b.h_max, c->val[R_MAX_WORK], work, n,
            h / n);
        return CF_STATUS_WARNING;
    }
    return CF_STATUS_OK;
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

/* ---- lifetime ------------------------------------------------------------------------ */
void cf_set_debug_logging(cf_inst *I, int on) { I->logging = on != 0; }

/* CRC-32 (zlib's) of n bytes: the table resource's checksum */
static uint64_t crc32_of(const unsigned char *p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return (uint64_t)(c ^ 0xFFFFFFFFu);
}

/* The local path of a file URI (file://localhost/p, file:///p, file:/p; anything else is
 * taken as a path), percent-decoded, into path (n bytes, cut there); its length. */
static size_t uri_to_path(const char *uri, char *path, size_t n) {
    const char *s = uri ? uri : "";
    if (strncmp(s, "file://localhost/", 17) == 0) s += 16;
    else if (strncmp(s, "file:///", 8) == 0) s += 7;
    else if (strncmp(s, "file:/", 6) == 0) s += 5;
    size_t k = 0;
    for (; *s && k + 1 < n; s++) { /* percent-decoding */
        unsigned hi, lo;
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
    return k;
}

/* the table resource (fmu_build/native_fmu.py, table_bytes): "cfmuTBL1", n1, n2, n3
 * (u32), the count of doubles (u64), the axes and the load nodes' patch coefficients and
 * spline (doubles: model.c's cf_model_attach_table), the
 * CRC-32 (zlib's) of all before it (u64); read from the resources folder (a file URI) at
 * instantiation into memory of the front end's; 0 with a logged reason */
static int load_table(Inst *I, const char *uri, const Inst *probe) {
    char path[4096];
    const size_t k = uri_to_path(uri, path, sizeof path);
    const char *name = "/table.bin";
    if (k && path[k - 1] == '/') name++;
    if (k + strlen(name) + 1 > sizeof path) {
        say(probe, CF_STATUS_ERROR, CF_MSG_RESOURCE_PATH, I->api,
            call_name(I, CF_CALL_INSTANTIATE));
        return 0;
    }
    strcat(path, name);
    const size_t n_data = (size_t)CF_T_N1 + CF_T_N2 + CF_T_N3 + CF_T_NCOEF;
    const size_t size = 8 + 12 + 8 + 8 * n_data + 8;
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        say(probe, CF_STATUS_ERROR, CF_MSG_TABLE_OPEN, I->api, call_name(I, CF_CALL_INSTANTIATE),
            path);
        return 0;
    }
    unsigned char *buf = (unsigned char *)I->cb.alloc(I->env, size + 1, 1);
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
        say(probe, CF_STATUS_ERROR, CF_MSG_TABLE_REFUSED, I->api,
            call_name(I, CF_CALL_INSTANTIATE), path, why);
        if (buf) I->cb.release(I->env, buf);
        return 0;
    }
    I->table = (double *)I->cb.alloc(I->env, n_data, sizeof(double));
    if (I->table) memcpy(I->table, buf + 28, 8 * n_data);
    I->cb.release(I->env, buf);
    if (I->table == NULL)
        say(probe, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, I->api,
            call_name(I, CF_CALL_INSTANTIATE));
    return I->table != NULL;
}

/* an instance that logs only (no model): for messages before there is an instance */
static void probe_for(Inst *probe, const cf_callbacks *cb, void *env, const char *api,
                      const char *name) {
    memset(probe, 0, sizeof *probe);
    probe->cb = *cb;
    probe->env = env;
    probe->api = api;
    probe->v3 = api != NULL && strcmp(api, "fmi3") == 0;
    probe->name = (char *)(name ? name : "");
}

void cf_log_to(const cf_callbacks *cb, void *env, const char *name, cf_status status,
               const char *fmt, ...) {
    if (cb == NULL) return;
    Inst probe;
    probe_for(&probe, cb, env, "", name);
    va_list ap;
    va_start(ap, fmt);
    vsay(&probe, status, fmt, ap);
    va_end(ap);
}

cf_inst *cf_instantiate(const char *api, const char *name, const char *guid,
                        const char *resource_uri, int logging, const cf_callbacks *cb,
                        void *env, size_t env_size) {
    if (cb == NULL || cb->alloc == NULL || cb->release == NULL) return NULL;
    Inst probe;
    probe_for(&probe, cb, env, api, name);
    if (guid == NULL || strcmp(guid, CF_GUID) != 0) {
        say(&probe, CF_STATUS_ERROR, CF_MSG_GUID, api, call_name(&probe, CF_CALL_INSTANTIATE),
            guid ? guid : "(null)", CF_GUID);
        return NULL;
    }
    /* the front end's bytes after the instance, aligned for any type */
    const size_t head = (sizeof(Inst) + sizeof(max_align_t) - 1) / sizeof(max_align_t) *
                        sizeof(max_align_t);
    Inst *I = (Inst *)cb->alloc(env, 1, head + env_size);
    if (I == NULL) {
        say(&probe, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, api,
            call_name(&probe, CF_CALL_INSTANTIATE));
        return NULL;
    }
    memset(I, 0, sizeof *I);
    I->cb = *cb;
    I->env = env_size ? (void *)((unsigned char *)I + head) : env;
    if (env_size) memcpy(I->env, env, env_size);
    I->api = api;
    I->v3 = probe.v3;
    size_t len = strlen(probe.name) + 1;
    I->name = (char *)I->cb.alloc(I->env, len, 1);
    if (I->name == NULL) {
        cb->release(env, I);
        say(&probe, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, api,
            call_name(&probe, CF_CALL_INSTANTIATE));
        return NULL;
    }
    memcpy(I->name, probe.name, len);
    if (CF_TABLE && !load_table(I, resource_uri, &probe)) {
        I->cb.release(I->env, I->name);
        cb->release(env, I);
        return NULL;
    }
    if (CF_GRID) {
        I->grid = (spin_grid *)I->cb.alloc(I->env, 1, sizeof(spin_grid));
        if (I->grid == NULL) {
            I->cb.release(I->env, I->name);
            cb->release(env, I);
            say(&probe, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, api,
                call_name(&probe, CF_CALL_INSTANTIATE));
            return NULL;
        }
        for (int k = 0; k < 5; k++) I->grid->key[k] = NAN;
        I->grid->strips.ny = 0;
    }
    if (CF_TRANSIENT) {
        I->field = (field_scratch *)I->cb.alloc(I->env, 1, sizeof(field_scratch));
        if (I->field == NULL) {
            if (I->grid) I->cb.release(I->env, I->grid);
            I->cb.release(I->env, I->name);
            cb->release(env, I);
            say(&probe, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, api,
                call_name(&probe, CF_CALL_INSTANTIATE));
            return NULL;
        }
    }
    I->logging = logging != 0;
    I->served = served_mask();
    start_values(I);
    return I;
}

void cf_free_instance(cf_inst *I) {
    if (I == NULL) return;
    for (size_t i = 0; i < I->cap_states; i++) /* the states the importer did not free */
        if (I->states[i]) I->cb.release(I->env, I->states[i]);
    if (I->states) I->cb.release(I->env, I->states);
    if (I->grid) I->cb.release(I->env, I->grid);
    if (I->field) I->cb.release(I->env, I->field);
    if (I->table) I->cb.release(I->env, I->table);
    I->cb.release(I->env, I->name);
    const cf_callbacks cb = I->cb; /* env may live in the instance: released last */
    cb.release(I->env, I);
}

/* ---- phases ------------------------------------------------------------------------- */
cf_status cf_setup_experiment(cf_inst *I, double start) {
    if (I->c.built) {
        say(I, CF_STATUS_ERROR, CF_MSG_SETUP_AFTER_INIT, I->api,
            call_name(I, CF_CALL_SETUP_EXPERIMENT));
        return CF_STATUS_ERROR;
    }
    if (isfinite(start)) {
        I->c.time = start;
        return CF_STATUS_OK;
    }
    char r[40];
    py_repr(start, r, sizeof r);
    say(I, CF_STATUS_ERROR, CF_MSG_START_TIME, r);
    return CF_STATUS_ERROR;
}

cf_status cf_enter_initialization_mode(cf_inst *I) {
    I->c.phase = PH_INIT;
    return CF_STATUS_OK;
}

cf_status cf_exit_initialization_mode(cf_inst *I) {
    if (I->c.phase == PH_INSTANTIATED) { /* FMI: only in initialisation mode */
        say(I, CF_STATUS_ERROR, CF_MSG_EXIT_BEFORE_ENTER, I->api, call_name(I, CF_CALL_ENTER_INIT));
        return CF_STATUS_ERROR;
    }
    I->c.init_tried = 1;
    if (!build(I)) { /* slave.exit_initialization_mode's refusal, its words */
        char list[1536];
        bad_list(I, list, sizeof list);
        say(I, CF_STATUS_ERROR, CF_MSG_CANNOT_START, list[0] ? list : CF_MSG_SEE_ABOVE);
        return CF_STATUS_ERROR;
    }
    I->c.phase = PH_STEP;
    return CF_STATUS_OK;
}

cf_status cf_terminate(cf_inst *I) {
    if (!I->c.built) { /* FMI: only once initialised; after an error: reset or free */
        say(I, CF_STATUS_ERROR, CF_MSG_TERMINATE_BEFORE_INIT, I->api,
            I->c.init_tried ? CF_MSG_FAILED : CF_MSG_NOT_CALLED);
        return CF_STATUS_ERROR;
    }
    I->c.phase = PH_TERMINATED;
    return CF_STATUS_OK;
}

unsigned cf_n_variables(void) { return CF_N_VARS; }

cf_status cf_reset(cf_inst *I) {
    start_values(I);
    return CF_STATUS_OK;
}

/* ---- variables ----------------------------------------------------------------------- */
static int vr_ok(const Inst *I, unsigned vr, int type, call_id call) {
    if (vr < CF_N_VARS && CF_VARS[vr].type == type) return 1;
    say(I, CF_STATUS_ERROR, CF_MSG_VR_TYPE, I->api, call_name(I, call), vr);
    return 0;
}

/* A value that was refused is held, not to be used: an error (slave._get) */
static cf_status held_bad(const Inst *I, unsigned vr) {
    if (!I->c.bad[vr]) return CF_STATUS_OK;
    char msg[256];
    bad_text(&CF_VARS[vr], I->c.var[vr], msg, sizeof msg);
    say(I, CF_STATUS_ERROR, CF_MSG_HELD_AT_GET, CF_VARS[vr].name, msg);
    return CF_STATUS_ERROR;
}

/* the contact mode's outputs to refresh for a get call: once for the call (its refusal
 * logged once), where it reads an output (a parameter or an input reads as it is) */
static cf_status refresh_for(Inst *I, const unsigned *vr, size_t n) {
    if (CF_MODE != MODE_CONTACT || !I->c.dirty || !I->c.built) return CF_STATUS_OK;
    for (size_t i = 0; i < n; i++)
        if (vr[i] < CF_N_VARS && CF_VARS[vr[i]].kind == K_OUTPUT) return refresh(I);
    return CF_STATUS_OK;
}

cf_status cf_get_real(cf_inst *I, const unsigned *vr, size_t n, double *v) {
    if (n > 0 && (vr == NULL || v == NULL)) return CF_STATUS_ERROR;
    cf_status status = refresh_for(I, vr, n);
    for (size_t i = 0; i < n; i++) {
        if (!vr_ok(I, vr[i], T_REAL, CF_CALL_GET_REAL)) return CF_STATUS_ERROR;
        v[i] = I->c.var[vr[i]];
        if (held_bad(I, vr[i]) != CF_STATUS_OK) status = CF_STATUS_ERROR;
    }
    return status;
}

int cf_line_size(void) { return CF_LINE ? CF_LINE_N : 0; }

/* the centre line's arrays (which: 0 x, 1 tau_x, 2 tau_y) at the outputs' kinematics: the
 * body's state (vx_slip, vy_slip, Vx, Omega_z), or the contact mode's inputs */
cf_status cf_get_line(cf_inst *I, int which, double *v) {
    if (!CF_LINE || which < 0 || which > 2 || v == NULL) return CF_STATUS_ERROR;
    static const char *const NAMES[3] = {"x_centre", "tau_x_centre", "tau_y_centre"};
    cf_core *c = &I->c;
    if (!c->built) {
        say(I, CF_STATUS_ERROR, CF_MSG_LINE_BEFORE_INIT, NAMES[which], I->api);
        return CF_STATUS_ERROR;
    }
    if (CF_MODE == MODE_CONTACT && c->dirty) {
        const cf_status s = refresh(I);
        if (s != CF_STATUS_OK) return s;
    }
    const double *o = c->b.out;
    const int contact = CF_MODE == MODE_CONTACT;
    const double Vx = contact ? c->val[R_VX] : o[O_VX];
    const double phi = contact ? c->val[R_OMEGA_Z] : o[O_OMEGA_Z];
    double line[3][CF_LINE_N];
    if (cf_model_centre_line(c, &c->p, &c->b, o[O_VX_SLIP], o[O_VY_SLIP], Vx, phi, line) != 0) {
        say(I, CF_STATUS_ERROR, CF_MSG_LINE_NOT_FINITE, NAMES[which], o[O_VX_SLIP],
            o[O_VY_SLIP], Vx, phi);
        return CF_STATUS_ERROR;
    }
    memcpy(v, line[which], sizeof line[which]);
    return CF_STATUS_OK;
}

cf_status cf_get_integer(cf_inst *I, const unsigned *vr, size_t n, int *v) {
    if (n > 0 && (vr == NULL || v == NULL)) return CF_STATUS_ERROR;
    cf_status status = refresh_for(I, vr, n);
    for (size_t i = 0; i < n; i++) {
        if (!vr_ok(I, vr[i], T_INTEGER, CF_CALL_GET_INTEGER)) return CF_STATUS_ERROR;
        const double x = I->c.var[vr[i]];
        if (CF_VARS[vr[i]].kind == K_OUTPUT) v[i] = x > 0.5 ? 1 : 0; /* regime, 0 or 1 */
        else v[i] = x >= INT_MIN && x <= INT_MAX ? (int)x : 0; /* nx, ny: set as int */
    }
    return status;
}

cf_status cf_get_boolean(cf_inst *I, const unsigned *vr, size_t n) {
    if (n == 0) return CF_STATUS_OK;
    say(I, CF_STATUS_ERROR, CF_MSG_NO_BOOLEAN, I->api, call_name(I, CF_CALL_GET_BOOLEAN),
        vr ? vr[0] : 0u);
    return CF_STATUS_ERROR;
}

cf_status cf_get_string(cf_inst *I, const unsigned *vr, size_t n, const char **v) {
    if (n > 0 && (vr == NULL || v == NULL)) return CF_STATUS_ERROR;
    for (size_t i = 0; i < n; i++) {
        if (!vr_ok(I, vr[i], T_STRING, CF_CALL_GET_STRING)) return CF_STATUS_ERROR;
        const int f = field_string((int)vr[i]);
        char *out = f >= 0 ? I->field_out[f] : is_scheme((int)vr[i]) ? I->scheme_out
                                                                        : I->method_out;
        snprintf(out, f >= 0 ? FIELD_TEXT : METHOD_TEXT, "%s", string_text(&I->c, (int)vr[i]));
        v[i] = out;
    }
    return CF_STATUS_OK;
}

/* a parameter or input may be set now; else the refusal logged */
static int settable(Inst *I, int i, const char *value) {
    const cf_var *v = &CF_VARS[i];
    if (v->kind == K_OUTPUT) {
        say(I, CF_STATUS_ERROR, CF_MSG_SET_OUTPUT, v->name, value);
        return 0;
    }
    if (v->kind == K_PARAMETER && I->c.built && v->role != R_MU) { /* mu is tunable */
        char now[80];
        if (v->type == T_STRING) snprintf(now, sizeof now, "'%s'", string_text(&I->c, i));
        else value_text(v, I->c.var[i], now, sizeof now);
        say(I, CF_STATUS_ERROR, CF_MSG_SET_FIXED, v->name, v->name, value, v->name, now);
        return 0;
    }
    return 1;
}

static void mark(cf_core *c, int i, int bad) {
    if (!bad) c->bad[i] = 0;
    else if (!c->bad[i]) c->bad[i] = ++c->next_bad;
}

cf_status cf_set_real(cf_inst *I, const unsigned *vr, size_t n, const double *v) {
    if (n > 0 && (vr == NULL || v == NULL)) return CF_STATUS_ERROR;
    cf_status status = CF_STATUS_OK;
    for (size_t k = 0; k < n; k++) {
        if (!vr_ok(I, vr[k], T_REAL, CF_CALL_SET_REAL)) return CF_STATUS_ERROR;
        const int i = (int)vr[k];
        const cf_var *var = &CF_VARS[i];
        char r[40] = "";
        if (var->kind == K_OUTPUT || (var->kind == K_PARAMETER && I->c.built))
            py_repr(v[k], r, sizeof r); /* for the refusal's message */
        if (!settable(I, i, r)) {
            status = CF_STATUS_ERROR;
            continue;
        }
        cf_core *C = &I->c;
        C->var[i] = v[k];
        if (var->role < R_COUNT) C->val[var->role] = v[k];
        const int bad = requirement(var, v[k]) != NULL;
        mark(C, i, bad);
        /* an input, or the tunable mu: a force element's outputs follow */
        if (var->kind == K_INPUT || (var->role == R_MU && !bad)) C->dirty = 1;
        if (bad) { /* refused: an error, the value held (as the pythonfmu FMU) */
            char msg[256];
            bad_text(var, v[k], msg, sizeof msg);
            say(I, CF_STATUS_ERROR, CF_MSG_HELD, msg, I->api);
            status = CF_STATUS_ERROR;
        }
    }
    return status;
}

/* the Integers: the output regime (refused) and phase "transient"'s nx and ny (the
 * Reals' rules: range, an integer, the value the build fixed) */
cf_status cf_set_integer(cf_inst *I, const unsigned *vr, size_t n, const int *v) {
    if (n > 0 && (vr == NULL || v == NULL)) return CF_STATUS_ERROR;
    cf_status status = CF_STATUS_OK;
    for (size_t k = 0; k < n; k++) {
        if (!vr_ok(I, vr[k], T_INTEGER, CF_CALL_SET_INTEGER)) return CF_STATUS_ERROR;
        const int i = (int)vr[k];
        const cf_var *var = &CF_VARS[i];
        char r[24];
        snprintf(r, sizeof r, "%d", v[k]);
        if (!settable(I, i, r)) {
            status = CF_STATUS_ERROR;
            continue;
        }
        cf_core *C = &I->c;
        C->var[i] = (double)v[k];
        if (var->role < R_COUNT) C->val[var->role] = (double)v[k];
        const int bad = requirement(var, (double)v[k]) != NULL;
        mark(C, i, bad);
        if (bad) {
            char msg[256];
            bad_text(var, (double)v[k], msg, sizeof msg);
            say(I, CF_STATUS_ERROR, CF_MSG_HELD, msg, I->api);
            status = CF_STATUS_ERROR;
        }
    }
    return status;
}

cf_status cf_set_boolean(cf_inst *I, const unsigned *vr, size_t n) {
    if (n == 0) return CF_STATUS_OK;
    say(I, CF_STATUS_ERROR, CF_MSG_NO_BOOLEAN, I->api, call_name(I, CF_CALL_SET_BOOLEAN),
        vr ? vr[0] : 0u);
    return CF_STATUS_ERROR;
}

cf_status cf_set_string(cf_inst *I, const unsigned *vr, size_t n, const char *const *v) {
    if (n > 0 && (vr == NULL || v == NULL)) return CF_STATUS_ERROR;
    cf_status status = CF_STATUS_OK;
    for (size_t k = 0; k < n; k++) {
        if (!vr_ok(I, vr[k], T_STRING, CF_CALL_SET_STRING)) return CF_STATUS_ERROR;
        const char *s = v[k] ? v[k] : "";
        char shown[METHOD_TEXT + 2];
        snprintf(shown, sizeof shown, "'%s'", s);
        if (!settable(I, (int)vr[k], shown)) {
            status = CF_STATUS_ERROR;
            continue;
        }
        cf_core *C = &I->c;
        const int i = (int)vr[k], scheme = is_scheme(i), f = field_string(i);
        if (f >= 0) { /* field_file, field_times (longer than the buffer: refused) */
            snprintf(C->field_text[f], FIELD_TEXT, "%s", s);
        } else {
            char *text = scheme ? C->scheme_text : C->method_text;
            int *choice = scheme ? &C->scheme : &C->method;
            snprintf(text, METHOD_TEXT, "%s", s);
            *choice = -1;
            for (int m = 0; m < (scheme ? N_SCHEMES : N_METHODS); m++)
                if (strcmp(s, (scheme ? SCHEME_NAMES : METHOD_NAMES)[m]) == 0) *choice = m;
        }
        /* RollingBody's check, at set-up in Python: here at once, the same words */
        const int bad = string_bad(C, i);
        mark(C, i, bad);
        if (bad) {
            char q[QUOTED], buf[80], msg[QUOTED + 256];
            snprintf(q, sizeof q, "'%s'", string_text(C, i));
            snprintf(msg, sizeof msg, CF_MSG_INVALID, CF_VARS[i].name, q,
                     string_requirement(C, i, buf, sizeof buf));
            say(I, CF_STATUS_ERROR, CF_MSG_HELD, msg, I->api);
            status = CF_STATUS_ERROR;
        }
    }
    return status;
}

/* ---- stepping ------------------------------------------------------------------------ */
cf_status cf_do_step(cf_inst *I, double t, double h) { return fmu_step(I, t, h); }

double cf_time(const cf_inst *I) { return I->c.time; }

/* Contact mode: the directional derivative of the outputs (z) along the inputs (u,
 * direction du) at the current inputs. Tx, Ty, Mz, vx, vy with respect to Vx, Vy,
 * Omega_y, Omega_z analytic (cf_model_contact_jacobian); any other pair (P, the
 * creepages, the adhesion) by central differences of the outputs along the direction.
 * A derivative that is not finite (inputs near overflow) is an error, never served. */
cf_status cf_directional_derivative(cf_inst *I, const unsigned *zr, size_t nz,
                                    const unsigned *ur, size_t nu, const double *du,
                                    double *dz) {
    if (CF_MODE != MODE_CONTACT) {
        say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_MODE, I->api,
            call_name(I, CF_CALL_DIRECTIONAL));
        return CF_STATUS_ERROR;
    }
    if ((nz && (zr == NULL || dz == NULL)) || (nu && (ur == NULL || du == NULL)))
        return CF_STATUS_ERROR;
    cf_core *C = &I->c;
    if (!C->built) {
        say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_BEFORE_INIT, I->api,
            call_name(I, CF_CALL_DIRECTIONAL));
        return CF_STATUS_ERROR;
    }
    if (C->next_bad && any_bad(C)) {
        say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_BAD_INPUT, I->api,
            call_name(I, CF_CALL_DIRECTIONAL));
        return CF_STATUS_ERROR;
    }
    if (C->dirty && refresh(I) != CF_STATUS_OK) return CF_STATUS_ERROR; /* logged there */
    int only_kin = 1; /* every known among (Vx, Vy, Omega_y, Omega_z) */
    double dir[4] = {0.0, 0.0, 0.0, 0.0};
    for (size_t j = 0; j < nu; j++) {
        if (ur[j] >= CF_N_VARS || CF_VARS[ur[j]].kind != K_INPUT || CF_VARS[ur[j]].type != T_REAL) {
            say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_VR, I->api,
                call_name(I, CF_CALL_DIRECTIONAL), ur[j], "input");
            return CF_STATUS_ERROR;
        }
        const int role = CF_VARS[ur[j]].role;
        const int k = role == R_VX ? 0 : role == R_VY ? 1 : role == R_OMEGA_Y ? 2
                    : role == R_OMEGA_Z ? 3 : -1;
        if (k < 0) only_kin = 0;
        else dir[k] += du[j];
        if (!isfinite(du[j])) {
            say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_DIRECTION, I->api,
                call_name(I, CF_CALL_DIRECTIONAL));
            return CF_STATUS_ERROR;
        }
    }
    /* central differences along the direction for what is not analytic */
    double plus[N_OUT], minus[N_OUT], eps = 0.0, J[3][4];
    int have_fd = 0, have_J = -1; /* -1: cf_model_contact_jacobian not yet called */
    size_t i;
    for (i = 0; i < nz; i++) {
        if (zr[i] >= CF_N_VARS || CF_VARS[zr[i]].kind != K_OUTPUT ||
            CF_VARS[zr[i]].type != T_REAL) {
            say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_VR, I->api,
                call_name(I, CF_CALL_DIRECTIONAL), zr[i], "output");
            return CF_STATUS_ERROR;
        }
        const int role = CF_VARS[zr[i]].role;
        double row[4];
        if (only_kin && have_J < 0 && role - R_OUT <= O_MZ && role - R_OUT >= O_TX)
            have_J = cf_model_contact_jacobian(C, I->grid, dir[3] != 0.0, J);
        if (only_kin && cf_model_analytic_row(C, role, have_J > 0, J, row)) {
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
                if (contact_outputs(I, &X, &p, &b, sgn ? minus : plus, r, sizeof r)) {
                    say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_NEAR, I->api,
                        call_name(I, CF_CALL_DIRECTIONAL));
                    return CF_STATUS_ERROR;
                }
            }
            have_fd = 1;
        }
        const int o = role - R_OUT;
        dz[i] = eps > 0.0 ? (plus[o] - minus[o]) / (2.0 * eps) : 0.0;
        if (!isfinite(dz[i])) goto not_finite;
    }
    return CF_STATUS_OK;
not_finite:
    say(I, CF_STATUS_ERROR, CF_MSG_DIRECTIONAL_NOT_FINITE, I->api,
        call_name(I, CF_CALL_DIRECTIONAL), CF_VARS[zr[i]].name);
    return CF_STATUS_ERROR;
}

/* ---- FMU state ------------------------------------------------------------------------ */
/* a restored core made safe: what no legal state holds is reset (constants, pointers,
 * flags); values are whatever they were (a non-finite one only makes steps decline) */
static void sanitize(cf_core *c) {
    cf_model_constants(&c->p, &c->b);
    c->method_text[METHOD_TEXT - 1] = '\0';
    c->scheme_text[METHOD_TEXT - 1] = '\0';
    c->field_text[0][FIELD_TEXT - 1] = c->field_text[1][FIELD_TEXT - 1] = '\0';
    for (int k = 0; k < (CF_TRANSIENT ? CF_FIELD_CAPTURES : 1); k++)
        for (int i = 0; i < FIELD_N; i++) c->cap[k].slip[i] = c->cap[k].slip[i] != 0;
    c->fs.sliding = c->fs.sliding != 0;
    for (int i = 0; i < FIELD_N; i++) c->fs.slip[i] = c->fs.slip[i] != 0;
    c->method = c->scheme = -1; /* the texts decide, as at setString */
    for (int m = 0; m < N_METHODS; m++)
        if (strcmp(c->method_text, METHOD_NAMES[m]) == 0) c->method = m;
    for (int m = 0; m < N_SCHEMES; m++)
        if (strcmp(c->scheme_text, SCHEME_NAMES[m]) == 0) c->scheme = m;
    c->p.quasistationary = c->method == 1;
    c->p.sdirk = c->scheme == 1;
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

/* the same double, NaN included (a state holds what the setter stored) */
static int same_double(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* all n doubles finite */
static int all_finite(const double *x, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* Why a sanitized core is not a state this FMU could have reached, in the words of the
 * pythonfmu FMU's check (slave._apply_state), or NULL: its phase and flags, every value
 * against its declared range with the record of the values held bad (the setters'
 * check, requirement), the outputs and the model's state finite. A state's envelope
 * (length, checksum) says nothing of its content: bytes made elsewhere can be intact. */
static const char *state_problem(const cf_core *c, char *why, size_t n) {
    char r[40];
    if (c->phase < PH_INSTANTIATED || c->phase > PH_TERMINATED || (c->built != 0) != c->built ||
        (c->dirty != 0) != c->dirty || (c->init_tried != 0) != c->init_tried ||
        (c->built && !c->init_tried)) {
        snprintf(why, n, CF_MSG_STATE_FLAGS, c->phase, c->built, c->dirty, c->init_tried);
        return why;
    }
    if (!isfinite(c->time)) {
        py_repr(c->time, r, sizeof r);
        snprintf(why, n, CF_MSG_STATE_TIME, r);
        return why;
    }
    for (int i = 0; i < CF_N_VARS; i++) {
        const cf_var *v = &CF_VARS[i];
        if (v->kind == K_OUTPUT) {
            if (c->bad[i] || !isfinite(c->var[i])) {
                py_repr(c->var[i], r, sizeof r);
                snprintf(why, n, CF_MSG_STATE_OUTPUT, v->name, r);
                return why;
            }
            continue;
        }
        int bad;
        char one[QUOTED + 256];
        if (v->type == T_STRING) {
            bad = string_bad(c, i);
        } else {
            if (v->role < R_COUNT && !same_double(c->val[v->role], c->var[i])) {
                snprintf(why, n, CF_MSG_STATE_DISAGREE, v->name);
                return why;
            }
            bad = requirement(v, c->var[i]) != NULL;
        }
        if (bad != (c->bad[i] != 0)) { /* the text of the value: only for the refusal */
            if (v->type == T_STRING) {
                char q[QUOTED];
                snprintf(q, sizeof q, "'%s'", string_text(c, i));
                snprintf(one, sizeof one, CF_MSG_STATE_NAMED, v->name, q);
            } else if (bad) {
                bad_text(v, c->var[i], one, sizeof one);
            } else {
                py_repr(c->var[i], r, sizeof r);
                snprintf(one, sizeof one, CF_MSG_STATE_NAMED, v->name, r);
            }
            snprintf(why, n, CF_MSG_STATE_RECORD, one, c->bad[i] ? "invalid" : "valid");
            return why;
        }
        if (bad && c->built && v->kind == K_PARAMETER && v->role != R_MU) {
            if (v->type == T_STRING) {
                char q[QUOTED];
                snprintf(q, sizeof q, "'%s'", string_text(c, i));
                snprintf(one, sizeof one, CF_MSG_STATE_NAMED, v->name, q);
            } else {
                bad_text(v, c->var[i], one, sizeof one);
            }
            snprintf(why, n, CF_MSG_STATE_PARAMS, one);
            return why;
        }
    }
    if (c->built) { /* the model's state: what its steps and outputs read */
        const cf_params *p = &c->p;
        const double law[] = {p->mu, p->P, p->a1, p->creep_full_slip, p->beta_per_creep,
                              p->M, p->Rx, p->A1, p->A2, p->m_slip, p->c, p->xi_ref,
                              p->phi_ref, c->b.a2, c->b.p0, c->b.h_max, c->P_law};
        const double body[] = {c->s.Vx, c->s.vx, c->s.t, c->s.dv, c->s.Tx, c->s.Ty, c->s.Mz,
                               c->vs.Vx, c->vs.vx, c->vs.Vy, c->vs.Oz, c->vs.t, c->vs.dv,
                               c->vs.Tx, c->vs.Ty, c->vs.Mz, c->vs.jac_h, c->rb_Vx,
                               c->rb_Omega_y};
        const int body_ok = CF_MODE != MODE_BODY ||
                            (all_finite(body, 7) && (!CF_VECTOR || all_finite(body + 7, 9)));
        const int rigid_ok = CF_MODE != MODE_RIGID || all_finite(body + 17, 2);
        const int law_ok = CF_MODE == MODE_RIGID || all_finite(law, CF_MODE == MODE_BODY ? 17 : 13);
        const int jac_ok = !(CF_MODE == MODE_BODY && CF_VECTOR && c->vs.jac_valid) ||
                           (isfinite(c->vs.jac_h) && all_finite(c->vs.J, 36));
        const cf_tstate *fs = &c->fs; /* phase "transient": the body and its field */
        const double lattice[] = {fs->t, fs->T[0], fs->T[1], fs->T[2], fs->theta,
                                  fs->direction, fs->dx, fs->X, fs->Y};
        const int field_ok = !CF_TRANSIENT ||
            (all_finite(fs->y, 4) && all_finite(fs->impulse, 3) && all_finite(lattice, 9) &&
             fs->dx > 0.0 && fs->X > 0.0 && fs->Y > 0.0 && fs->theta >= 0.0 && fs->theta <= 1.0 &&
             (fs->direction == 0.0 || fabs(fs->direction) == 1.0) &&
             all_finite(fs->ys, CF_FIELD_NY) && all_finite(fs->dy, CF_FIELD_NY) &&
             all_finite(fs->tau_x, FIELD_N) && all_finite(fs->tau_y, FIELD_N) &&
             all_finite(fs->fo, N_OUT_ALL - N_OUT));
        double times[CF_FIELD_CAPTURES];
        const int m = c->field_text[0][0] ? cf_model_field_times(c->field_text[1], times) : 0;
        int captures_ok = !CF_TRANSIENT || (c->n_captured >= 0 && c->n_captured <= m);
        for (int q = 0; captures_ok && q < c->n_captured; q++) {
            const cf_capture *cq = &c->cap[q];
            const double at[] = {cq->wanted, cq->t, cq->theta, cq->direction, cq->a1, cq->a2,
                                 cq->p0, cq->mu, cq->P};
            captures_ok = all_finite(at, 9) && cq->a1 > 0.0 && cq->a2 > 0.0 &&
                          all_finite(cq->tau_x, FIELD_N) && all_finite(cq->tau_y, FIELD_N);
        }
        if (!(body_ok && rigid_ok && law_ok && jac_ok && field_ok && captures_ok &&
              all_finite(c->b.out, N_OUT))) {
            snprintf(why, n, CF_MSG_STATE_MODEL, CF_MSG_STATE_MODEL_NOT_FINITE);
            return why;
        }
    }
    return NULL;
}

/* The live states: FMI 2.0 forbids passing back a freed state or one of another
 * instance, but a pointer that is not a live state of this instance is refused
 * (an error, the pythonfmu FMU's words: pythonfmu_shim.c) instead of being read. The
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
        cf_core **grown = (cf_core **)I->cb.alloc(I->env, cap, sizeof *grown);
        if (grown == NULL) return 0;
        memset(grown, 0, cap * sizeof *grown);
        cf_core **was = I->states;
        I->states = grown, I->cap_states = cap, I->n_states = 0;
        for (size_t i = 0; i < old; i++)
            if (was[i]) put(I, was[i]);
        if (was) I->cb.release(I->env, was);
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

static int live_or_refuse(const Inst *I, const void *st, call_id call) {
    if (live(I, st)) return 1;
    char pointer[40];
    snprintf(pointer, sizeof pointer, "%p", (void *)(uintptr_t)st);
    say(I, CF_STATUS_ERROR, CF_MSG_NOT_A_STATE, I->api, call_name(I, call), pointer);
    return 0;
}

/* *state: NULL for a new state, else a live one to overwrite (FMI 2.0); NULL if out of
 * memory or refused (logged) */
static cf_core *state_to_fill(Inst *I, void **state, call_id call) {
    if (*state != NULL) return live_or_refuse(I, *state, call) ? (cf_core *)*state : NULL;
    cf_core *s = (cf_core *)I->cb.alloc(I->env, 1, sizeof(cf_core));
    if (s != NULL && keep(I, s)) return s;
    if (s != NULL) I->cb.release(I->env, s);
    say(I, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, I->api, call_name(I, call));
    return NULL;
}

cf_status cf_get_state(cf_inst *I, void **state) {
    if (state == NULL) {
        say(I, CF_STATUS_ERROR, CF_MSG_NO_PLACE, I->api, call_name(I, CF_CALL_GET_STATE), "state");
        return CF_STATUS_ERROR;
    }
    cf_core *s = state_to_fill(I, state, CF_CALL_GET_STATE);
    if (s == NULL) return CF_STATUS_ERROR;
    *s = I->c;
    *state = s;
    return CF_STATUS_OK;
}

cf_status cf_set_state(cf_inst *I, const void *state) {
    if (state == NULL) {
        say(I, CF_STATUS_ERROR, CF_MSG_NO_STATE, I->api, call_name(I, CF_CALL_SET_STATE));
        return CF_STATUS_ERROR;
    }
    if (!live_or_refuse(I, state, CF_CALL_SET_STATE)) return CF_STATUS_ERROR;
    /* checked on a copy (on the heap: a transient field's core is hundreds of kB) */
    cf_core *c = (cf_core *)I->cb.alloc(I->env, 1, sizeof(cf_core));
    if (c == NULL) {
        say(I, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, I->api, call_name(I, CF_CALL_SET_STATE));
        return CF_STATUS_ERROR;
    }
    *c = *(const cf_core *)state;
    sanitize(c);
    char why[2 * QUOTED + 512];
    if (state_problem(c, why, sizeof why)) { /* slave._set_fmu_state's words */
        char refused[sizeof why + 128];
        I->cb.release(I->env, c);
        snprintf(refused, sizeof refused, CF_MSG_STATE_REFUSED, why);
        say(I, CF_STATUS_ERROR, CF_MSG_STATE_UNCHANGED, refused);
        return CF_STATUS_ERROR;
    }
    const int captured = I->c.n_captured;
    I->c = *c;
    I->cb.release(I->env, c);
    cf_model_attach_table(I->table, &I->c.p);
    if (CF_TRANSIENT && I->c.built && I->c.field_text[0][0] && I->c.n_captured != captured) {
        char err[256]; /* FieldRecorder.set_state: rewritten, best effort */
        cf_model_field_write(I->c.field_text[0], I->c.cap, I->c.n_captured,
                             I->c.val[R_KB] + I->c.val[R_KS], &I->c.fs, I->field, err,
                             sizeof err);
    }
    if (CF_VECTOR && I->c.built) ensure_grid(I, &I->c.p, &I->c.b, &I->c.p); /* its load's */
    return CF_STATUS_OK;
}

cf_status cf_free_state(cf_inst *I, void **state) {
    if (state == NULL) {
        say(I, CF_STATUS_ERROR, CF_MSG_NO_STATE, I->api, call_name(I, CF_CALL_FREE_STATE));
        return CF_STATUS_ERROR;
    }
    if (*state == NULL) return CF_STATUS_OK; /* the standard: nothing to free */
    if (!live_or_refuse(I, *state, CF_CALL_FREE_STATE)) return CF_STATUS_ERROR;
    forget(I, *state);
    I->cb.release(I->env, *state);
    *state = NULL;
    return CF_STATUS_OK;
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

cf_status cf_serialized_size(cf_inst *I, const void *state, size_t *size) {
    if (size == NULL) {
        say(I, CF_STATUS_ERROR, CF_MSG_NO_PLACE, I->api, call_name(I, CF_CALL_STATE_SIZE), "size");
        return CF_STATUS_ERROR;
    }
    if (!live_or_refuse(I, state, CF_CALL_STATE_SIZE)) return CF_STATUS_ERROR;
    *size = serialized_size();
    return CF_STATUS_OK;
}

cf_status cf_serialize(cf_inst *I, const void *state, unsigned char *out, size_t size) {
    if (!live_or_refuse(I, state, CF_CALL_SERIALIZE)) return CF_STATUS_ERROR;
    if (out == NULL || size < serialized_size()) {
        say(I, CF_STATUS_ERROR, CF_MSG_SERIALIZE_BUFFER, I->api, call_name(I, CF_CALL_SERIALIZE),
            size, serialized_size());
        return CF_STATUS_ERROR;
    }
    unsigned char *p = out;
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
    return CF_STATUS_OK;
}

cf_status cf_deserialize(cf_inst *I, const unsigned char *in, size_t size, void **state) {
    const unsigned char *p = in;
    const char *why = NULL;
    uint32_t version = 0, glen = 0;
    uint64_t plen = 0, sum = 0;
    char length[128];
    if (p == NULL || state == NULL) why = CF_MSG_NO_BYTES;
    else if (size < sizeof MAGIC + 8 || memcmp(p, MAGIC, sizeof MAGIC) != 0)
        why = CF_MSG_NOT_SERIALIZED;
    if (why == NULL) {
        memcpy(&version, p + 8, 4);
        memcpy(&glen, p + 12, 4);
        if (version != STATE_VERSION) why = CF_MSG_OTHER_VERSION;
        else if (glen != strlen(CF_GUID) || size < 16 + (size_t)glen ||
                 memcmp(p + 16, CF_GUID, glen) != 0)
            why = CF_MSG_OTHER_FMU;
    }
    if (why == NULL) {
        if (size != serialized_size()) {
            snprintf(length, sizeof length, CF_MSG_LENGTH_DIFFERS, CF_MSG_LENGTH_OF_STATES);
            why = length;
        } else {
            memcpy(&plen, p + 16 + glen, 8);
            memcpy(&sum, p + size - 8, 8);
            if (plen != sizeof(cf_core)) why = CF_MSG_PAYLOAD_DIFFERS;
            else if (fnv1a(p, size - 8) != sum) why = CF_MSG_CHECKSUM_DIFFERS;
        }
    }
    if (why != NULL) {
        say(I, CF_STATUS_ERROR, CF_MSG_BYTES_REFUSED, I->api, call_name(I, CF_CALL_DESERIALIZE),
            size, why);
        return CF_STATUS_ERROR;
    }
    cf_core *c = (cf_core *)I->cb.alloc(I->env, 1, sizeof(cf_core)); /* on the heap */
    if (c == NULL) {
        say(I, CF_STATUS_ERROR, CF_MSG_OUT_OF_MEMORY, I->api,
            call_name(I, CF_CALL_DESERIALIZE));
        return CF_STATUS_ERROR;
    }
    memcpy(c, p + 16 + glen + 8, sizeof(cf_core));
    sanitize(c);
    char problem[2 * QUOTED + 512];
    if (state_problem(c, problem, sizeof problem)) {
        I->cb.release(I->env, c);
        say(I, CF_STATUS_ERROR, CF_MSG_BYTES_REFUSED, I->api, call_name(I, CF_CALL_DESERIALIZE),
            size, problem);
        return CF_STATUS_ERROR;
    }
    cf_core *s = state_to_fill(I, state, CF_CALL_DESERIALIZE);
    if (s != NULL) *s = *c;
    I->cb.release(I->env, c);
    if (s == NULL) return CF_STATUS_ERROR;
    *state = s;
    return CF_STATUS_OK;
}
