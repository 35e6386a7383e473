/* The native FMU's model numerics outside the kernel (stepper.c): the constants of the
 * Python integrator and the law at a load into the kernel's parameters, the contact
 * mode's outputs (fmu/contact_model.py: the thin-layer law's closed form, with a spin
 * input by the strip march on the law's spin grid, or the creep-force table), the
 * rigid_body mode's step (fmu/rigid_body.py) and the contact mode's analytic directional
 * derivatives. No FMI here and no message: the instance layer (instance.c) checks,
 * words and commits. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#ifdef _WIN32
#include <direct.h>
#define make_dir(p) _mkdir(p)
#else
#include <sys/stat.h>
#define make_dir(p) mkdir((p), 0777)
#endif

#include "model.h"

/* Python's max(x, c) for a constant c: x unless c is strictly larger */
static double py_max(double x, double c) { return c > x ? c : x; }

#if CF_T_NLOADS > CF_LOADS_MAX
#error "more load nodes than CF_LOADS_MAX (the build refuses such a table)"
#endif

/* the creep-force table's arrays into p (after cf_model_constants): the axes, each load
 * node's patches in turn (CF_T_STRIDE doubles each), and with several nodes the spline of
 * their weights in log P and their onsets of full slip (stepper.c's load_weights) */
void cf_model_attach_table(const double *table, cf_params *p) {
    if (!CF_TABLE || table == NULL) return;
    p->ax1 = table;
    p->ax2 = p->ax1 + CF_T_N1;
    p->ax3 = p->ax2 + CF_T_N2;
    p->coef = p->ax3 + CF_T_N3;
    p->n1 = CF_T_N1, p->n2 = CF_T_N2, p->n3 = CF_T_N3;
    p->ext1 = p->ax1[CF_T_N1 - 1], p->ext2 = p->ax2[CF_T_N2 - 1], p->ext3 = p->ax3[CF_T_N3 - 1];
    p->n_loads = CF_T_NLOADS;
    p->spline_k = CF_T_SPLINE_K;
    p->spline = CF_T_NLOADS > 1 ? p->coef + (size_t)CF_T_NLOADS * CF_T_STRIDE : NULL;
}

void cf_model_constants(cf_params *p, cf_body *b) {
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
    p->coef = p->ax1 = p->ax2 = p->ax3 = NULL; /* the table's: cf_model_attach_table */
    p->strips = NULL;
    p->dyn_vy = p->dyn_spin = 0;
    p->rz = 0.0;
    p->Iz = 0.0;
    p->n_loads = 0, p->spline_k = 0, p->spline = NULL; /* the table's: cf_model_attach_table */
    b->v_creep_floor = CF_V_CREEP_FLOOR;
    b->substep_slack = CF_SUBSTEP_SLACK;
    b->max_substeps = CF_MAX_SUBSTEPS;
}

/* the law at load P into p and b (its reported a2, p0) */
void cf_model_law_at_load(const cf_core *c, double P, cf_params *p, cf_body *b) {
    const double *v = c->val;
    if (CF_TABLE) { /* the nodes' weights at P: stepper.c (its patches and onset) */
        cf_table_law(p, P, v[R_MU], CF_T_KFAC, CF_T_M, CF_T_AMIN, CF_T_A_LE_B, CF_T_ESTAR,
                     CF_T_G, CF_T_ONSET, &b->a2, &b->p0);
        return;
    }
    cf_layer_law(p, P, v[R_RX], v[R_RY], v[R_K1], v[R_K2], v[R_KB], v[R_KS], v[R_MU], &b->a2,
                 &b->p0);
}

/* the spin grid g for the law at its load (p, b: a1, a2, p0 there) with the parameters
 * of c (mu, kb + ks), built unless it is already for these */
const cf_strips *cf_model_grid(spin_grid *g, const cf_core *c, const cf_params *law,
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
    cf_law_forces(p, vx, vy, Vx, T);
    cf_march_standstill(g, vx, vy, phi, with);
    cf_march_standstill(g, vx, vy, 0.0, without);
    for (int k = 0; k < 3; k++) T[k] += with[k] - without[k];
}

/* ContactElement.evaluate: the law at the inputs' load and kinematics, rigid slip of
 * Eq. (3) at the contact centre (kinematics.rigid_slip), the forces (the closed form,
 * LayerContact._forces_scalar, or with a spin input Omega_z != 0 LayerContact.forces
 * by the strip march on the spin grid g, built here for the load) and
 * kinematics.contact_quantities; p and b hold the law at the load afterwards. The index
 * into out of the first output served that is not finite (cf_first_nonfinite), or -1. */
int cf_model_contact_outputs(const cf_core *c, spin_grid *g, cf_params *p, cf_body *b,
                             double out[N_OUT], unsigned long served) {
    const double *v = c->val;
    if (v[R_P] != p->P || v[R_MU] != p->mu) cf_model_law_at_load(c, v[R_P], p, b); /* mu: tunable */
    const double Vx = v[R_VX], vx = Vx - v[R_OMEGA_Y] * v[R_RX], vy = v[R_VY];
    const double Omega_z = v[R_OMEGA_Z];
    double T[3], tab[4];
    const cf_strips *grid = NULL;
    if (CF_TABLE) {
        cf_table_forces(p, vx, vy, Omega_z, Vx, tab); /* CreepTable._scalar, spin included */
        T[0] = tab[0], T[1] = tab[1], T[2] = tab[2];
    } else if (CF_CONTACT_SPIN && Omega_z != 0.0 && g != NULL) {
        grid = cf_model_grid(g, c, p, b);
        spin_forces(p, grid, vx, vy, Omega_z, Vx, T);
    } else {
        cf_law_forces(p, vx, vy, Vx, T);
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
                             : cf_adhesion_fraction(p, vx, vy, Vx);
    /* with spin the creepage alone does not tell gross sliding: no adhesion area left
     * does (ContactElement.evaluate) */
    out[O_REGIME] = (Omega_z != 0.0 ? !(out[O_ADHESION] > 0.0) : cf_full_slip(p, vx, vy, Vx))
                        ? 1.0 : 0.0;
    return cf_first_nonfinite(out, served);
}

/* RigidBody.step (rigid_body.py): Eqs. (8)-(9) under held inputs, exact: Vx += h (Fx_ex
 * - Tx)/M, Omega_y += h (My_ex + Rx Tx)/Iy, into out (the other outputs 0) */
void cf_model_rigid_step(const cf_core *c, double h, double out[N_OUT]) {
    const double *v = c->val;
    const double Tx = v[R_TX];
    for (int i = 0; i < N_OUT; i++) out[i] = 0.0;
    out[O_VX] = c->rb_Vx + h * (v[R_FX_EX] - Tx) / v[R_M];
    out[O_OMEGA_Y] = c->rb_Omega_y + h * (v[R_MY_EX] + v[R_RX] * Tx) / v[R_IY];
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
        const double d = muP * cf_force_fraction_slope(p, 0.0) * c / aV;
        const double dg = -0.5; /* g'(0) = (h(0) - 1)/2 */
        double Z[3][3] = {{d, 0.0, 0.0}, {0.0, d, 0.0}, {0.0, sg * muP * a1 * dg * c / aV, 0.0}};
        memcpy(J, Z, sizeof Z);
        return;
    }
    const double ex = vx / s, ey = vy / s, beta = s * c / aV;
    double h = 1.0, dh = 0.0, dg = 0.0; /* g = beta (h - 1)/2 enters as g/|v| (g_s) */
    if (beta < p->beta_full_slip) {
        h = cf_force_fraction(p, beta);
        dh = cf_force_fraction_slope(p, beta);
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

/* d(Tx, Ty, Mz)/d(vx, vy, V, phi) of what cf_model_contact_outputs computes at the current
 * inputs (the law at their load in c->p), rolling (V != 0) on the thin-layer law: the
 * closed form's (law_jacobian) and, with a spin phi != 0, the march with the spin less
 * the march without it differentiated in forward mode (cf_march_jacobian), whose phi
 * column is the only one in phi. At phi = 0 the FMU computes the closed form alone, and
 * the phi column is the march's slope there (the correction's, which vanishes at 0;
 * marched only where the direction has a component in phi: need_phi). 0 where no
 * analytic form is had: standstill, the table. */
int cf_model_contact_jacobian(const cf_core *c, spin_grid *grid, int need_phi, double J[3][4]) {
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
    if (CF_CONTACT_SPIN && grid != NULL && (phi != 0.0 || need_phi)) {
        const cf_strips *g = cf_model_grid(grid, c, &c->p, &c->b);
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
 * cf_model_contact_jacobian's, have: whether there is one), else 0 */
int cf_model_analytic_row(const cf_core *c, int role, int have, double J[3][4], double row[4]) {
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

/* The strip march (Eq. 35 bounded by Eqs. 4-5: cf_strip_march) of one strip, the centre
 * line y = 0, from the leading edge; at standstill every point slides, tau = mu p v/|v|
 * (Eq. 5, v of Eq. 3 at y = 0: vx + i (vy + phi x)), as layer._Grid._march_numpy. */
int cf_model_centre_line(const cf_core *c, const cf_params *law, const cf_body *b, double vx,
                         double vy, double Vx, double phi, double line[3][CF_LINE_N]) {
    enum { N = CF_LINE_N };
    double y[1], dist[N], mid[N], cap[N], w[N], tau[2 * N];
    unsigned char inside[N], slip[N];
    cf_strips g;
    memset(line, 0, 3 * sizeof line[0]);
    const double in[4] = {vx, vy, Vx, phi};
    for (int k = 0; k < 4; k++)
        if (!isfinite(in[k])) return -1;
    if (law->P == 0.0 || !(law->a1 > 0.0)) return 0; /* lift-off: no contact, no traction */
    const double *v = c->val;
    cf_grid_build(&g, line[0], y, dist, mid, cap, w, inside, N, 1, law->a1, b->a2, b->p0,
                  law->mu, v[R_KB] + v[R_KS], CF_TINY);
    if (Vx != 0.0) {
        if (cf_strip_march(&g, 1, &vx, &vy, &Vx, &phi, tau, slip) != CF_OK) return -1;
        for (int j = 0; j < N; j++) { /* march order: against x for Vx > 0 */
            const int e = Vx > 0.0 ? N - 1 - j : j;
            line[1][j] = tau[2 * e], line[2][j] = tau[2 * e + 1];
        }
        return 0;
    }
    for (int j = 0; j < N; j++) {
        const double sx = vx, sy = vy + phi * line[0][j], mag = hypot(sx, sy);
        if (mag > 0.0) line[1][j] = cap[j] * sx / mag, line[2][j] = cap[j] * sy / mag;
    }
    return 0;
}

/* ---- phase "transient": the body on the thin-layer traction field -------------------- */

/* LayerField.__init__ (transient.py) at the law's load: dx = 2 a1/nx, X = a1, Y = a2, the
 * strips of _strips("sine", ny, a2): phi at the midpoints of ny intervals of (-pi/2,
 * pi/2), y = a2 sin(phi), dy = a2 cos(phi) dphi; the field at rest (theta = 0.5, no
 * rolling yet, tau = 0, no slip) */
void cf_model_field_lay(const cf_params *law, const cf_body *lb, cf_tstate *fs) {
    const double dphi = M_PI / CF_FIELD_NY;
    fs->dx = 2.0 * law->a1 / CF_FIELD_NX;
    fs->X = law->a1;
    fs->Y = lb->a2;
    for (int i = 0; i < CF_FIELD_NY; i++) {
        const double phi = -0.5 * M_PI + ((double)i + 0.5) * dphi;
        fs->ys[i] = lb->a2 * sin(phi);
        fs->dy[i] = lb->a2 * cos(phi) * dphi;
    }
    fs->theta = 0.5;
    fs->direction = 0.0;
    memset(fs->tau_x, 0, sizeof fs->tau_x);
    memset(fs->tau_y, 0, sizeof fs->tau_y);
    memset(fs->slip, 0, sizeof fs->slip);
}

/* LayerField._update_contact at the law's load: l(y) = a1 sqrt(max(1 - (y/a2)^2, 0))
 * (Eq. 37), p at x = 0: p0 (1 - (y/a2)^2), the strip widths scaled so that the rule
 * integrates the pressure to P (sum dy_w (4/3) p0 l^3/a1^2 = P; numpy's dot sums in
 * another order: the scale agrees to rounding); c0 = mu p0/a1^2 (Eq. 33); k = kb + ks */
void cf_model_field(const cf_params *law, const cf_body *lb, double k, const cf_tstate *fs,
                    field_scratch *sc, cf_field *f) {
    const double a1 = law->a1, a2 = lb->a2, p0 = lb->p0, a1sq = pow(a1, 2.0);
    double held = 0.0;
    for (int i = 0; i < CF_FIELD_NY; i++) {
        const double q = fs->ys[i] / a2, r = 1.0 - q * q;
        sc->ell[i] = a1 * sqrt(r > 0.0 ? r : 0.0);
        sc->p_strip[i] = p0 * r;
        held += fs->dy[i] * ((4.0 / 3.0) * p0 * pow(sc->ell[i], 3.0) / a1sq);
    }
    const double scale = held > 0.0 ? law->P / held : 1.0;
    for (int i = 0; i < CF_FIELD_NY; i++) sc->dy_w[i] = fs->dy[i] * scale;
    f->ny = CF_FIELD_NY, f->nx = CF_FIELD_NX;
    f->dx = fs->dx, f->X = fs->X;
    f->a1 = a1, f->p0 = p0, f->mu = law->mu, f->k = k;
    f->c0 = law->mu * p0 / a1sq;
    f->min_speed_fraction = CF_FIELD_MIN_SPEED_FRACTION;
    f->y = fs->ys, f->ell = sc->ell, f->p_strip = sc->p_strip, f->dy_w = sc->dy_w;
}

/* TransientRollingBody.outputs(): the kinematics of the state (BodyState.kinematics),
 * the contact of the last step (T, sliding), the creepages (kinematics.creepage: |Vx|
 * floored at V_CREEP_FLOOR), the law's a1, a2, p0, and LayerField.summary (adhesion,
 * slip-area centroid, peak |tau|: cf_field_summary) */
int cf_model_field_outputs(const cf_params *law, const cf_body *lb, const cf_field *f,
                           cf_tstate *fs, field_scratch *sc, double out[N_OUT_ALL]) {
    double s[4];
    const int rc = cf_field_summary(f, fs->theta, fs->tau_x, fs->tau_y, fs->slip, s, sc->work,
                                    sc->bytes);
    const double Vx = fs->y[0], vx = fs->y[1], Vy = fs->y[2], Oz = fs->y[3];
    const double V = py_max(fabs(Vx), CF_V_CREEP_FLOOR);
    for (int i = 0; i < N_OUT_ALL; i++) out[i] = 0.0;
    out[O_VX] = Vx, out[O_VY] = Vy, out[O_OMEGA_Y] = (Vx - vx) / law->Rx, out[O_OMEGA_Z] = Oz;
    out[O_TX] = fs->T[0], out[O_TY] = fs->T[1], out[O_MZ] = fs->T[2];
    out[O_VX_SLIP] = vx, out[O_VY_SLIP] = Vy;
    out[O_XI_X] = vx / V, out[O_XI_Y] = Vy / V, out[O_XI_SP] = Oz / V;
    out[O_A1] = law->a1, out[O_A2] = lb->a2, out[O_P0] = lb->p0;
    out[O_REGIME] = fs->sliding ? 1.0 : 0.0;
    if (rc != CF_FIELD_OK) return rc;
    out[O_ADHESION] = s[0];
    out[O_SLIP_CX] = s[1], out[O_SLIP_CY] = s[2], out[O_TAU_PEAK] = s[3];
    for (int k = 0; k < N_OUT_ALL - N_OUT; k++) fs->fo[k] = out[N_OUT + k];
    return CF_FIELD_OK;
}

/* ---- the field file (body_transient.FieldRecorder) ----------------------------------- */

static int by_value(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int cf_model_field_times(const char *text, double times[CF_FIELD_CAPTURES]) {
    int n = 0;
    const char *s = text;
    for (;;) {
        while (*s == ' ' || *s == ',' || *s == ';' || *s == '\t' || *s == '\n' || *s == '\r')
            s++;
        if (*s == '\0') break;
        char *end;
        const double t = strtod(s, &end);
        if (end == s || !(*end == '\0' || *end == ' ' || *end == ',' || *end == ';' ||
                          *end == '\t' || *end == '\n' || *end == '\r'))
            return -1;
        if (!isfinite(t)) return -2;
        if (n == CF_FIELD_CAPTURES) return -3;
        times[n++] = t;
        s = end;
    }
    qsort(times, (size_t)n, sizeof times[0], by_value);
    return n;
}

/* the folders of path made (Path.parent.mkdir(parents=True, exist_ok=True)) */
static void make_parents(const char *path) {
    char dir[FIELD_TEXT];
    snprintf(dir, sizeof dir, "%s", path);
    for (char *q = dir + 1; *q; q++)
        if (*q == '/' || *q == '\\') {
            const char keep = *q;
            *q = '\0';
            make_dir(dir); /* an existing one: EEXIST, fine; a failure shows at fopen */
            *q = keep;
        }
}

/* LayerField.traction_field / arrays of a capture, one row per node: requested, time, i,
 * j, x, y, tau_x, tau_y (0 outside the contact), p (Eq. 33, 0 outside), slip, inside,
 * weight (LayerField._weights at the field's direction: cf_field_weights), as numpy's
 * savetxt writes them (%.17g, %d) */
int cf_model_field_write(const char *path, const cf_capture *cap, int n, double k,
                         const cf_tstate *fs, field_scratch *sc, char *why, size_t why_size) {
    make_parents(path);
    errno = 0;
    FILE *out = fopen(path, "w");
    if (out == NULL) {
        snprintf(why, why_size, "%s", strerror(errno));
        return -1;
    }
    fprintf(out, "requested,time,i,j,x,y,tau_x,tau_y,p,slip,inside,weight\n");
    double x[CF_FIELD_NX];
    for (int c = 0; c < n; c++) {
        const cf_capture *q = &cap[c];
        cf_params law;
        cf_body lb;
        memset(&law, 0, sizeof law);
        memset(&lb, 0, sizeof lb);
        law.a1 = q->a1, law.mu = q->mu, law.P = q->P, lb.a2 = q->a2, lb.p0 = q->p0;
        cf_field f;
        cf_model_field(&law, &lb, k, fs, sc, &f);
        for (int j = 0; j < CF_FIELD_NX; j++) x[j] = -fs->X + ((double)j + q->theta) * fs->dx;
        unsigned char *inside = sc->bytes;
        for (int i = 0; i < CF_FIELD_NY; i++)
            for (int j = 0; j < CF_FIELD_NX; j++)
                inside[i * CF_FIELD_NX + j] = fabs(x[j]) < sc->ell[i];
        double *w = sc->work + 3 * CF_FIELD_NX; /* after the weights' own scratch */
        if (cf_field_weights(&f, x, inside, q->tau_x, q->tau_y, q->slip, q->direction, w,
                             sc->work) != CF_FIELD_OK) {
            fclose(out);
            snprintf(why, why_size, "the field's weights are not finite");
            return -1;
        }
        for (int i = 0; i < CF_FIELD_NY; i++)
            for (int j = 0; j < CF_FIELD_NX; j++) {
                const int e = i * CF_FIELD_NX + j;
                const double qx = x[j] / q->a1, qy = fs->ys[i] / q->a2;
                const double r = 1.0 - qx * qx - qy * qy;
                fprintf(out, "%.17g,%.17g,%d,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%d,%.17g\n",
                        q->wanted, q->t, i, j, x[j], fs->ys[i], inside[e] ? q->tau_x[e] : 0.0,
                        inside[e] ? q->tau_y[e] : 0.0, q->p0 * (r > 0.0 ? r : 0.0),
                        q->slip[e] != 0, inside[e], w[e]);
            }
    }
    const int bad = ferror(out) != 0;
    if (fclose(out) != 0 || bad) {
        snprintf(why, why_size, "%s", errno ? strerror(errno) : "the write failed");
        return -1;
    }
    return 0;
}
