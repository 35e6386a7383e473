/* Compiled twin of integrator.RollingBody.advance on its Lobatto IIIC and SDIRK2 paths
 * (cf_params.sdirk picks the scheme: integrator.SCHEMES).
 *
 * The path: the thin-layer law (layer.LayerContact, Eqs. 40-43 corrected) or the
 * half-space creep-force table (halfspace/table.py), with lateral slip and spin held
 * at ratios to Vx or zero, the body of Eqs. (8)-(9) and (20) with vx the only stage
 * unknown (with a spin: the stage slope by the forward difference of RollingBody._law_x), loads held over the interval, methods "full" and
 * "quasistationary". Every expression is that of the Python code, in the same order,
 * and the build forbids contraction to fused multiply-adds, so a step of the thin-layer
 * law without lateral slip gives the same doubles as the Python path; with lateral slip
 * (CPython's hypot is not the C library's) and for the table (its patch sums run in
 * another order than numpy's) the two agree to rounding (tests/test_native.py).
 *
 * Whatever this file does not cover returns CF_FALLBACK with the state untouched, and
 * the Python path takes the whole interval: a stage whose safeguarded Newton iteration
 * does not converge (Python then brackets and calls brentq; with params.bracket, as in
 * the native FMU, this file does the same, to the same doubles), a stage with no root
 * (Python raises StageSolveError with its message), and any non-finite input, state or
 * result (a load that overflows the step): no function here turns a double it receives
 * into an index or a loop count without checking it.
 *
 * Then the strip march of the thin-layer law with spin (layer._Grid.march), which
 * the Python steppers call: one loop of the same operations; and, at the end, the
 * Lobatto IIIC and SDIRK2 steps with Vy and/or Omega_z as stage unknowns
 * (_lobatto_vector, _sdirk_vector), which agree with the Python path to the stage
 * tolerance.
 */
#include <float.h>
#include <math.h>
#include <stddef.h>

#include "stepper.h"

/* all n doubles finite */
static int finite_all(const double *x, int n) {
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* The last zero-spin march of forces_at: a Jacobian column in Omega_z changes only
 * the spin, so its march without spin is the one before (the same doubles). */
typedef struct {
    int valid;
    double vx, vy, V, R[3];
} march_cache;

/* the law at a state (Vx, vx, Vy, Omega_z), below v_standstill blended (further down) */
static void forces_at(const cf_params *p, const double y[4], double T[3], march_cache *c);

/* Python's min(x, c) and max(x, c) for a constant c: the first argument unless c is
 * strictly smaller (larger). */
static double py_min(double x, double c) { return c < x ? c : x; }
static double py_max(double x, double c) { return c > x ? c : x; }

/* P = 0: lift-off, no contact (LayerContact.lifted): every force, slope and the adhesion
 * are zero, and the steps are free_step's */
static int lifted(const cf_params *p) { return p->P == 0.0; }

/* ---- layer.py ------------------------------------------------------------------- */
/* m = (1 - b^2/4)^(1/2), common to H(b) of Eq. (42), corrected, and its slope */
static double m_of(double b) { return sqrt(1.0 - 0.25 * b * b); }

static double H_m(double b, double m) {
    return (1.0 + b * b) * asin(0.5 * b) - 0.5 * M_PI * b * b + b * m * (13.0 / 6.0 + b * b / 12.0);
}

/* dh/dbeta below full slip (layer._force_fraction_slope) */
static double slope_m(double b, double m) {
    return py_max((2.0 / M_PI) * (m * (8.0 + b * b) / 3.0 - 2.0 * b * asin(m)), 0.0);
}

static double force_fraction(const cf_params *p, double beta) {
    if (beta >= p->beta_full_slip) return 1.0;
    return py_min((2.0 / M_PI) * H_m(beta, m_of(beta)), 1.0);
}

static double force_fraction_slope(const cf_params *p, double beta) {
    if (beta >= p->beta_full_slip) return 0.0;
    return slope_m(beta, m_of(beta));
}

/* LayerContact._forces_scalar: (Tx, Ty, Mz) */
static void forces(const cf_params *p, double vx, double vy, double Vx, double T[3]) {
    double speed = hypot(vx, vy);
    if (speed == 0.0 || lifted(p)) {
        T[0] = T[1] = T[2] = 0.0;
        return;
    }
    double beta = Vx == 0.0 ? INFINITY : speed * p->beta_per_creep / fabs(Vx);
    double h = force_fraction(p, beta);
    double muP = p->mu * p->P;
    double b = py_min(beta, p->beta_full_slip);
    double g = 0.5 * b * (h - 1.0);
    T[2] = Vx != 0.0 ? copysign(1.0, Vx) * muP * p->a1 * g * vy / speed : 0.0;
    T[0] = muP * h * vx / speed;
    T[1] = muP * h * vy / speed;
}

/* LayerContact.tx_slope: Tx, dTx/dvx, dTx/dvy, dTx/dVx */
static void tx_slope(const cf_params *p, double vx, double vy, double Vx, double r[4]) {
    if (lifted(p)) {
        r[0] = r[1] = r[2] = r[3] = 0.0;
        return;
    }
    double muP = p->mu * p->P, c = p->beta_per_creep;
    double aV = fabs(Vx);
    double s = hypot(vx, vy);
    if (s == 0.0) {
        r[0] = 0.0;
        r[1] = muP * force_fraction_slope(p, 0.0) * c / aV;
        r[2] = 0.0;
        r[3] = 0.0;
        return;
    }
    double ex = vx / s, ey = vy / s;
    double beta = s * c / aV;
    /* force_fraction, force_fraction_slope and fraction_per_beta of one beta, their
     * common terms (m, h) taken once: the same operations */
    double h = 1.0, dh = 0.0;
    if (beta < p->beta_full_slip) {
        double m = m_of(beta);
        h = py_min((2.0 / M_PI) * H_m(beta, m), 1.0);
        dh = slope_m(beta, m);
    }
    double per_beta = beta < p->beta_series
        ? 16.0 / (3.0 * M_PI) - beta + 2.0 * beta * beta / (3.0 * M_PI)
        : h / beta;
    double h_per_s = per_beta * c / aV;
    r[0] = muP * h * ex;
    r[1] = muP * (dh * c * ex * ex / aV + h_per_s * ey * ey);
    r[2] = muP * ex * ey * (dh * c / aV - h_per_s);
    r[3] = -muP * dh * beta * ex / Vx;
}

/* ---- halfspace/table.py: CreepTable, scalar paths without spin --------------------- */
/* The patch sums run in a fixed order here and through numpy there: this law agrees with
 * the Python one to rounding, not bit for bit. */
static int cell(const double *ax, int n, double x) { /* min(max(bisect_right - 1, 0), n - 2) */
    int lo = 0, hi = n; /* first index with ax[i] > x */
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (x < ax[mid]) hi = mid;
        else lo = mid + 1;
    }
    int i = lo - 1;
    return i < 0 ? 0 : (i > n - 2 ? n - 2 : i);
}

/* CreepTable._weights: the load nodes' weights at P (n_loads > 1): the interpolating
 * spline of degree k in log P through the unit vectors (make_interp_spline(log P_j,
 * eye(n), k): its knots t and coefficients c in p->spline), at log P clamped to the
 * nodes (the first node's at P = 0), evaluated as scipy's BSpline: the interval t[l] <=
 * x < t[l + 1] (l < n), de Boor's recursion for the k + 1 B-splines there (_deBoor_D),
 * then for each weight the sum over their coefficients in order; the same operations. */
static void load_weights(const cf_params *p, double P, double w[CF_LOADS_MAX]) {
    const int n = p->n_loads, k = p->spline_k;
    const double lo = p->spline[0], hi = p->spline[1];
    const double *t = p->spline + 2, *c = t + n + k + 1;
    double x = lo;
    if (P > 0.0) { /* np.clip(math.log(P), lo, hi) */
        x = log(P);
        x = x < lo ? lo : (x > hi ? hi : x);
    }
    int l = k;
    while (l + 1 < n && x >= t[l + 1]) l++;
    double h[4] = {1.0, 0.0, 0.0, 0.0}, hh[4];
    for (int j = 1; j <= k; j++) {
        for (int i = 0; i < j; i++) hh[i] = h[i];
        h[0] = 0.0;
        for (int m = 1; m <= j; m++) {
            const double xb = t[l + m], xa = t[l + m - j];
            if (xb == xa) {
                h[m] = 0.0;
                continue;
            }
            const double f = hh[m - 1] / (xb - xa);
            h[m - 1] += f * (xb - x);
            h[m] = f * (x - xa);
        }
    }
    for (int j = 0; j < n; j++) {
        double sum = 0.0;
        for (int a = 0; a <= k; a++) sum = sum + c[(size_t)(l + a - k) * n + j] * h[a];
        w[j] = sum;
    }
}

/* the Hermite patch of cell (i1, i2, i3) at the law's load: the table's own (one node),
 * or (n_loads > 1) CreepTable._coefficients_at's weighted sum of the nodes' patches,
 * sum(w_j C_j) from 0 in the nodes' order (the same operations as numpy's elementwise
 * sum), for this cell only, into blend */
static const double *patch(const cf_params *p, int i1, int i2, int i3, double blend[256]) {
    const size_t at = ((size_t)((i1 * (p->n2 - 1) + i2) * (p->n3 - 1) + i3)) * 256;
    if (p->n_loads <= 1) return p->coef + at;
    const size_t stride = (size_t)(p->n1 - 1) * (size_t)(p->n2 - 1) * (size_t)(p->n3 - 1) * 256;
    double w[CF_LOADS_MAX];
    load_weights(p, p->P, w);
    for (int e = 0; e < 256; e++) blend[e] = 0.0;
    for (int j = 0; j < p->n_loads; j++) {
        const double *C = p->coef + (size_t)j * stride + at;
        for (int e = 0; e < 256; e++) blend[e] = blend[e] + w[j] * C[e];
    }
    return blend;
}

/* sum over the 64 Hermite terms of w[a b c] = T1[a] T2[b] T3[c] times output o */
static double patch_sum(const double *C, const double T1[4], const double T2[4],
                        const double T3[4], int o) {
    double f = 0.0;
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++)
            for (int c = 0; c < 4; c++)
                f += T1[a] * T2[b] * T3[c] * C[(a * 16 + b * 4 + c) * 4 + o];
    return f;
}

static double saturate(double m, double w) {
    if (m <= 1.0 - w) return m;
    if (m >= 1.0) return 1.0;
    double t = (m - (1.0 - w)) / w;
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    return 1.0 - w + w * (t + t * t - pow(t, 3.0));
}

/* CreepTable._scalar: (Tx, Ty, Mz, adhesion) */
static void table_scalar(const cf_params *p, double vx, double vy, double phi, double Vx,
                         double out[4]) {
    if (lifted(p)) { /* CreepTable.lifted */
        out[0] = out[1] = out[2] = out[3] = 0.0;
        return;
    }
    double sV = Vx < 0.0 ? -1.0 : 1.0, aV = fabs(Vx);
    double d[3] = {sV * vx / p->xi_ref, vy / p->xi_ref, sV * phi / p->phi_ref};
    if (!(isfinite(d[0]) && isfinite(d[1]) && isfinite(d[2]))) {
        /* slips beyond double range in table units: v and Vx over their largest (the
         * same creepages, a direction within range) */
        double m = py_max(py_max(fabs(vx), fabs(vy)), fabs(phi));
        aV = aV / m;
        d[0] = sV * (vx / m) / p->xi_ref;
        d[1] = (vy / m) / p->xi_ref;
        d[2] = sV * (phi / m) / p->phi_ref;
    }
    double X[3] = {p->ext1, p->ext2, p->ext3};
    double lam = INFINITY;
    for (int i = 0; i < 3; i++)
        if (d[i] != 0.0) lam = py_min(lam, X[i] / fabs(d[i]));
    if (lam == INFINITY) lam = 0.0;                        /* no slip at all */
    else if (aV > 0.0 && lam * aV >= 1.0) lam = 1.0 / aV; /* inside the box: x = d/|Vx| */
    /* else on the box's face, x = d lam, whatever Vx (lam |Vx| may underflow: no
     * product with it; Vx = 0 is the limit) */
    double x1 = d[0] * lam, x2 = d[1] * lam, x3 = d[2] * lam, sg = 1.0;
    if (x1 < 0.0 || (x1 == 0.0 && (x2 < 0.0 || (x2 == 0.0 && x3 < 0.0)))) {
        sg = -1.0;
        x1 = -x1;
        x2 = -x2;
        x3 = -x3;
    }
    int i1 = cell(p->ax1, p->n1, x1), i2 = cell(p->ax2, p->n2, x2), i3 = cell(p->ax3, p->n3, x3);
    double t1 = (x1 - p->ax1[i1]) / (p->ax1[i1 + 1] - p->ax1[i1]);
    double t2 = (x2 - p->ax2[i2]) / (p->ax2[i2 + 1] - p->ax2[i2]);
    double t3 = (x3 - p->ax3[i3]) / (p->ax3[i3 + 1] - p->ax3[i3]);
    double T1[4] = {1.0, t1, t1 * t1, t1 * t1 * t1}, T2[4] = {1.0, t2, t2 * t2, t2 * t2 * t2};
    double T3[4] = {1.0, t3, t3 * t3, t3 * t3 * t3};
    double blend[256];
    const double *C = patch(p, i1, i2, i3, blend);
    double fx = sg * patch_sum(C, T1, T2, T3, 0), fy = sg * patch_sum(C, T1, T2, T3, 1);
    double mz = sg * patch_sum(C, T1, T2, T3, 2), adh = patch_sum(C, T1, T2, T3, 3);
    double m = hypot(fx, fy);
    if (m > 1.0 - p->saturation_width) {
        double sat = saturate(m, p->saturation_width);
        fx = fx * sat / m;
        fy = fy * sat / m;
    }
    double muP = p->mu * p->P;
    out[0] = sV * muP * fx;
    out[1] = muP * fy;
    out[2] = sV * muP * p->c * mz;
    out[3] = py_min(py_max(adh, 0.0), 1.0);
}

/* CreepTable.tx_slope: Tx, dTx/dvx, dTx/dvy, dTx/dVx (Vx != 0) */
static void table_tx_slope(const cf_params *p, double vx, double vy, double Vx, double r[4]) {
    if (lifted(p)) {
        r[0] = r[1] = r[2] = r[3] = 0.0;
        return;
    }
    double sV = Vx < 0.0 ? -1.0 : 1.0, aV = fabs(Vx), xr = p->xi_ref;
    double d[2] = {sV * vx / xr, vy / xr}, ext[2] = {p->ext1, p->ext2};
    double lam = INFINITY;
    int j = -1;
    for (int i = 0; i < 2; i++)
        if (d[i] != 0.0 && ext[i] / fabs(d[i]) < lam) {
            lam = ext[i] / fabs(d[i]);
            j = i;
        }
    double dd[2] = {sV / xr, 1.0 / xr}, x[2], J[2][3];
    if (j < 0 || lam * aV >= 1.0) { /* inside the box: x = d/|Vx| */
        x[0] = d[0] / aV;
        x[1] = d[1] / aV;
        J[0][0] = dd[0] / aV, J[0][1] = 0.0, J[0][2] = -x[0] * sV / aV;
        J[1][0] = 0.0, J[1][1] = dd[1] / aV, J[1][2] = -x[1] * sV / aV;
    } else { /* on the face of axis j: x = d X_j/|d_j|, independent of Vx */
        x[0] = d[0] * lam;
        x[1] = d[1] * lam;
        for (int i = 0; i < 2; i++) {
            for (int k = 0; k < 2; k++)
                J[i][k] = lam * ((double)(i == k) - (k == j ? d[i] / d[j] : 0.0)) * dd[k];
            J[i][2] = 0.0;
        }
    }
    double x1 = x[0], x2 = x[1], sg = 1.0;
    if (x1 < 0.0 || (x1 == 0.0 && x2 < 0.0)) {
        sg = -1.0;
        x1 = -x1;
        x2 = -x2;
    }
    int i1 = cell(p->ax1, p->n1, x1), i2 = cell(p->ax2, p->n2, x2), i3 = cell(p->ax3, p->n3, 0.0);
    double h1 = p->ax1[i1 + 1] - p->ax1[i1], h2 = p->ax2[i2 + 1] - p->ax2[i2];
    double t1 = (x1 - p->ax1[i1]) / h1, t2 = (x2 - p->ax2[i2]) / h2;
    double t3 = (0.0 - p->ax3[i3]) / (p->ax3[i3 + 1] - p->ax3[i3]);
    double T1[4] = {1.0, t1, t1 * t1, pow(t1, 3.0)}, dT1[4] = {0.0, 1.0, 2.0 * t1, 3.0 * t1 * t1};
    double T2[4] = {1.0, t2, t2 * t2, pow(t2, 3.0)}, dT2[4] = {0.0, 1.0, 2.0 * t2, 3.0 * t2 * t2};
    double T3[4] = {1.0, t3, t3 * t3, pow(t3, 3.0)};
    double blend[256];
    const double *C = patch(p, i1, i2, i3, blend);
    double fx = sg * patch_sum(C, T1, T2, T3, 0), fy = sg * patch_sum(C, T1, T2, T3, 1);
    double dfx[2] = {patch_sum(C, dT1, T2, T3, 0) / h1, patch_sum(C, T1, dT2, T3, 0) / h2};
    double dfy[2] = {patch_sum(C, dT1, T2, T3, 1) / h1, patch_sum(C, T1, dT2, T3, 1) / h2};
    double m = hypot(fx, fy), w = p->saturation_width, dox[2], outx;
    if (m > 1.0 - w) {
        double tt = py_min((m - (1.0 - w)) / w, 1.0);
        double sat = m < 1.0 ? 1.0 - w + w * (tt + tt * tt - pow(tt, 3.0)) : 1.0;
        double ds = m < 1.0 ? 1.0 + 2.0 * tt - 3.0 * tt * tt : 0.0;
        double S = sat / m, dS = (ds * m - sat) / (m * m);
        dox[0] = S + fx * dS * fx / m;
        dox[1] = fx * dS * fy / m;
        outx = fx * S;
    } else {
        dox[0] = 1.0;
        dox[1] = 0.0;
        outx = fx;
    }
    double dx_out[2];
    for (int a = 0; a < 2; a++) dx_out[a] = dox[0] * dfx[a] + dox[1] * dfy[a];
    double muP = p->mu * p->P;
    r[0] = sV * muP * outx;
    for (int k = 0; k < 3; k++) r[k + 1] = sV * muP * (dx_out[0] * J[0][k] + dx_out[1] * J[1][k]);
}

/* ---- integrator.py -------------------------------------------------------------- */
/* the law's Tx and its slopes (dTx/dvx, dTx/dvy, dTx/dV) at speed V */
static void slope_at(const cf_params *p, double vx, double vy, double V, double r[4]) {
    if (p->law == LAW_TABLE) table_tx_slope(p, vx, vy, V, r);
    else tx_slope(p, vx, vy, V, r);
}

static void law(const cf_params *p, double vx, double Vx, double T[3]);

/* RollingBody._law_x: Tx and dTx/dvx along a stage path (slope, k); below
 * v_standstill the blend of integrator.forces_at_rest and its slope; with a held spin
 * (rz != 0: the laws' slopes have no spin) the forward difference of step fd_step (|vx|
 * + scale) */
static void law_x(const cf_params *p, double vx, double Vx, double k, double scale,
                  double out[2]) {
    const double vs = p->v_standstill, vy = p->ry * Vx;
    if (p->rz != 0.0) {
        double T[3], Td[3];
        law(p, vx, Vx, T);
        const double dv = p->fd_step * (fabs(vx) + scale);
        law(p, vx + dv, Vx + k * dv, Td);
        out[0] = T[0];
        out[1] = (Td[0] - T[0]) / dv;
        return;
    }
    if (fabs(Vx) >= vs) {
        double r[4];
        slope_at(p, vx, vy, Vx, r);
        out[0] = r[0];
        out[1] = r[1] + k * p->ry * r[2] + k * r[3];
        return;
    }
    double w = 0.5 * (1.0 + Vx / vs), rp[4], rm[4];
    slope_at(p, vx, vy, vs, rp);
    slope_at(p, vx, vy, -vs, rm);
    double sp = rp[1] + k * p->ry * rp[2], sm = rm[1] + k * p->ry * rm[2];
    out[0] = w * rp[0] + (1.0 - w) * rm[0];
    out[1] = w * sp + (1.0 - w) * sm + k * (rp[0] - rm[0]) / (2.0 * vs);
}

/* RollingBody._law: (Tx, Ty, Mz) at slip vx and speed Vx, lateral slip ry Vx, spin rz
 * Vx: the vector path's forces_at (the blend of integrator.forces_at_rest below
 * v_standstill) at that state; without spin it marches nothing */
static void law(const cf_params *p, double vx, double Vx, double T[3]) {
    const double y[4] = {Vx, vx, p->ry * Vx, p->rz * Vx};
    march_cache unused = {0, 0.0, 0.0, 0.0, {0.0, 0.0, 0.0}};
    forces_at(p, y, T, &unused);
}

/* the stage residuals: algebraic (T(v, V2b) - Fe2) or Lobatto's coupled pair (g) */
typedef struct {
    const cf_params *p;
    double V1b, V2b, Fe1, Fe2, vn, h, m, k, scale;
} stage;

static void residual_algebraic(const stage *s, double v, double f[2]) {
    double o[2];
    law_x(s->p, v, s->V2b + s->k * (v - s->vn), s->k, s->scale, o);
    f[0] = o[0] - s->Fe2;
    f[1] = o[1];
}

static void residual_lobatto(const stage *s, double v2, double f[2]) {
    double o2[2], o1[2];
    law_x(s->p, v2, s->V2b + s->k * (v2 - s->vn), s->k, s->scale, o2);
    double v1 = v2 - s->h * (s->Fe2 - o2[0]) / s->m;
    double dv1 = 1.0 + s->h * o2[1] / s->m;
    law_x(s->p, v1, s->V1b + s->k * (v1 - s->vn), s->k, s->scale, o1);
    f[0] = o1[0] - s->Fe1 + s->m * (v1 + v2 - 2.0 * s->vn) / s->h;
    f[1] = o1[1] * dv1 + s->m * (dv1 + 1.0) / s->h;
}

/* scipy.optimize.brentq (scipy/optimize/Zeros/brentq.c, Brent 1973: inverse quadratic
 * interpolation, secant or bisection inside a shrinking bracket), the same operations:
 * the root of f(s, .) in [xa, xb] to xtol + rtol |x|; CF_FALLBACK if f has one sign at
 * both ends or iter iterations do not converge (scipy raises). */
static int brentq(const stage *s, void (*fdf)(const stage *, double, double[2]), double xa,
                  double xb, double xtol, double rtol, int iter, double *root) {
    double xpre = xa, xcur = xb, xblk = 0.0, fblk = 0.0, spre = 0.0, scur = 0.0;
    double f[2];
    fdf(s, xpre, f);
    double fpre = f[0];
    fdf(s, xcur, f);
    double fcur = f[0];
    if (fpre == 0.0) return *root = xpre, CF_OK;
    if (fcur == 0.0) return *root = xcur, CF_OK;
    if (signbit(fpre) == signbit(fcur)) return CF_FALLBACK;
    for (int i = 0; i < iter; i++) {
        if (fpre != 0.0 && fcur != 0.0 && signbit(fpre) != signbit(fcur)) {
            xblk = xpre;
            fblk = fpre;
            spre = scur = xcur - xpre;
        }
        if (fabs(fblk) < fabs(fcur)) {
            xpre = xcur, xcur = xblk, xblk = xpre;
            fpre = fcur, fcur = fblk, fblk = fpre;
        }
        const double delta = (xtol + rtol * fabs(xcur)) / 2;
        const double sbis = (xblk - xcur) / 2;
        if (fcur == 0.0 || fabs(sbis) < delta) return *root = xcur, CF_OK;
        if (fabs(spre) > delta && fabs(fcur) < fabs(fpre)) {
            double stry;
            if (xpre == xblk) { /* interpolate */
                stry = -fcur * (xcur - xpre) / (fcur - fpre);
            } else { /* extrapolate */
                const double dpre = (fpre - fcur) / (xpre - xcur);
                const double dblk = (fblk - fcur) / (xblk - xcur);
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre));
            }
            const double lim = 3 * fabs(sbis) - delta;
            if (2 * fabs(stry) < (fabs(spre) < lim ? fabs(spre) : lim)) { /* short step */
                spre = scur;
                scur = stry;
            } else { /* bisect */
                spre = sbis;
                scur = sbis;
            }
        } else { /* bisect */
            spre = sbis;
            scur = sbis;
        }
        xpre = xcur;
        fpre = fcur;
        if (fabs(scur) > delta) xcur += scur;
        else xcur += (sbis > 0 ? delta : -delta);
        fdf(s, xcur, f);
        fcur = f[0];
    }
    return CF_FALLBACK;
}

/* solvers.increasing_root (max_step inf): the bracket grows from u0 in steps scale,
 * EXPAND scale, ... until the residual changes sign, then brentq closes it to
 * SOLVE_RTOL (scale + |lo| + |hi|); CF_FALLBACK where Python raises (no sign change in
 * max_expansions steps: no root) */
static int increasing_root(const stage *s, void (*fdf)(const stage *, double, double[2]),
                           double u0, double scale, double *root) {
    const cf_params *p = s->p;
    double f[2];
    fdf(s, u0, f);
    const double r0 = f[0];
    if (r0 == 0.0) return *root = u0, CF_OK;
    const double direction = r0 > 0.0 ? -1.0 : 1.0;
    double step = scale, a = u0, b = u0;
    int k = 0;
    for (; k < p->max_expansions; k++) {
        b = a + direction * step;
        fdf(s, b, f);
        if ((f[0] > 0.0) != (r0 > 0.0)) break;
        a = b;
        step *= p->expand;
    }
    if (k == p->max_expansions) return CF_FALLBACK;
    const double lo = a < b ? a : b, hi = a < b ? b : a;
    const double tol = p->solve_rtol * (scale + fabs(lo) + fabs(hi));
    return brentq(s, fdf, lo, hi, tol, 4 * DBL_EPSILON, 200, root);
}

/* solvers.newton_increasing; its fallback (increasing_root) here where p->bracket,
 * else CF_FALLBACK */
static int newton_increasing(const stage *s, void (*fdf)(const stage *, double, double[2]),
                             double u0, double scale, double *root) {
    double lo = -INFINITY, hi = INFINITY, u = u0, jump = scale, f[2];
    for (int i = 0; i < s->p->max_newton; i++) {
        fdf(s, u, f);
        if (f[0] == 0.0) {
            *root = u;
            return CF_OK;
        }
        if (f[0] > 0.0) hi = u;
        else lo = u;
        double next = f[1] > 0.0 ? u - f[0] / f[1] : NAN;
        if (fabs(next - u) <= s->p->solve_rtol * (scale + fabs(u))) {
            *root = next;
            return CF_OK;
        }
        if (!(lo < next && next < hi)) {
            if (isfinite(lo) && isfinite(hi)) {
                next = 0.5 * (lo + hi);
            } else {
                next = u + (f[0] < 0.0 ? jump : -jump);
                jump *= s->p->expand;
            }
        }
        if (fabs(next - u) <= s->p->solve_rtol * (scale + fabs(u))) {
            *root = next;
            return CF_OK;
        }
        u = next;
    }
    return s->p->bracket ? increasing_root(s, fdf, u0, scale, root) : CF_FALLBACK;
}

static double target_x(const cf_params *p, double Fx, double My) {
    return p->A2 * Fx - p->A1 * My / p->Rx;
}

static double drive(const cf_params *p, double Fx, double My) {
    return p->A1 * (Fx + My / p->Rx);
}

/* RollingBody._admissible (no lateral force on this path: Ty = 0) */
static int admissible(const cf_params *p, double Fx, double My) {
    double cap = p->mu * p->P * (1.0 - p->capacity_margin);
    return hypot(target_x(p, Fx, My), 0.0) < cap;
}

/* kinematics.is_full_slip */
static int full_slip(const cf_params *p, double vx, double vy, double Vx) {
    double speed = hypot(vx, vy);
    return speed > 0.0 && speed >= p->creep_full_slip * fabs(Vx);
}

/* is_full_slip at the state (vy = ry Vx, _apply_ratios) */
static int saturated(const cf_params *p, double Vx, double vx) {
    return full_slip(p, vx, p->ry * Vx, Vx);
}

/* RollingBody._lobatto_scalar with held loads (L1 = L2) */
static int lobatto_scalar(const cf_params *p, cf_state *y, double h, double Fx, double My,
                          int algebraic, double T[3]) {
    double Vn = y->Vx, vn = y->vx;
    double G1 = drive(p, Fx, My), G2 = G1;
    double Fe1 = target_x(p, Fx, My), Fe2 = Fe1;
    stage s = {p, 0, 0, Fe1, Fe2, vn, h, 0, 0, 0};
    s.V1b = Vn + 0.5 * h * (G1 - G2) / p->M;
    s.V2b = Vn + 0.5 * h * (G1 + G2) / p->M;
    s.scale = p->creep_full_slip * py_max(fabs(s.V2b), p->v_scale_floor);
    s.m = algebraic ? 0.0 : p->m_slip;
    s.k = s.m / p->M;
    double slope = p->mu * p->P / s.scale;
    double v2;
    if (s.m == 0.0 || h * slope / s.m > p->z_algebraic) { /* Vx = V2b + k (v2 - vn) */
        if (newton_increasing(&s, residual_algebraic, vn + y->dv * h, s.scale, &v2))
            return CF_FALLBACK;
        const double V2 = s.V2b + s.k * (v2 - vn);
        law(p, v2, V2, T);
        T[0] = Fe2;
        y->Vx = V2;
        y->vx = v2;
        return CF_OK;
    }
    if (newton_increasing(&s, residual_lobatto, vn + y->dv * h, s.scale, &v2))
        return CF_FALLBACK;
    double V2 = s.V2b + s.k * (v2 - vn);
    law(p, v2, V2, T);
    y->Vx = V2;
    y->vx = v2;
    return CF_OK;
}

/* RollingBody._sdirk_scalar's stage residual m (v - v_hat)/(h gamma) + T(v) - Fe and its
 * slope, in the fields of the Lobatto stage: Vb in V2b, Fe in Fe2, v_hat in vn, h gamma
 * in h */
static void residual_sdirk(const stage *s, double v, double f[2]) {
    double o[2];
    law_x(s->p, v, s->V2b + s->k * (v - s->vn), s->k, s->scale, o);
    f[0] = s->m * (v - s->vn) / s->h + o[0] - s->Fe2;
    f[1] = s->m / s->h + o[1];
}

/* RollingBody._sdirk_scalar with held loads (L1 = L2): two sequential stages, v_hat_1 =
 * vn, v_hat_2 = vn + (1 - gamma)/gamma (v1 - vn) (v1 in the algebraic limit m = 0), the
 * speed's explicit part likewise; the force closes the last stage's balance */
static int sdirk_scalar(const cf_params *p, cf_state *y, double h, double Fx, double My,
                        int algebraic, double T[3]) {
    const double g = p->gamma, hg = h * g;
    const double Vn = y->Vx, vn = y->vx;
    const double G = drive(p, Fx, My), Fe = target_x(p, Fx, My);
    stage s = {p, 0, 0, Fe, Fe, vn, hg, 0, 0, 0};
    s.m = algebraic ? 0.0 : p->m_slip;
    s.k = s.m / p->M;
    double V_hat = Vn, v = 0.0, V = 0.0;
    for (int i = 0; i < 2; i++) {
        s.V2b = V_hat + hg * G / p->M;
        s.scale = p->creep_full_slip * py_max(fabs(s.V2b), p->v_scale_floor);
        if (newton_increasing(&s, residual_sdirk, s.vn + y->dv * hg, s.scale, &v))
            return CF_FALLBACK;
        V = s.V2b + s.k * (v - s.vn);
        if (i == 0) { /* the explicit part of stage 2 from stage 1's slope */
            V_hat = Vn + (1.0 - g) / g * (V - Vn);
            s.vn = s.m > 0.0 ? vn + (1.0 - g) / g * (v - vn) : v;
        }
    }
    law(p, v, V, T);
    T[0] = Fe - s.m * (v - s.vn) / hg;
    y->Vx = V;
    y->vx = v;
    return CF_OK;
}

/* RollingBody._free_step, held loads: the step without contact (P = 0), Eqs. (8)-(9)
 * with T = 0 and the scheme's quadrature weights (exact for held loads); Iy = 0 takes
 * no moment (CF_FALLBACK: Python raises), Omega_y held without one. The state Y =
 * (Vx, vx, Vy, Omega_z); dyn_vy, dyn_spin: Vy, Omega_z by Eqs. (10)-(11), else the
 * held ratios. The slip rate into *dv. */
static int free_step(const cf_params *p, double Y[4], double h, const double L[4], int dyn_vy,
                     int dyn_spin, double *dv) {
    const double w1 = p->sdirk ? 1.0 - p->gamma : 0.5, w2 = p->sdirk ? p->gamma : 0.5;
    const double Fx = w1 * L[0] + w2 * L[0], My = w1 * L[2] + w2 * L[2];
    if (p->Iy == 0.0 && L[2] != 0.0) return CF_FALLBACK;
    const double Vn = Y[0], vn = Y[1];
    const double dV = h * Fx / p->M;
    const double vx = vn + dV - (p->Iy > 0.0 ? h * p->Rx * My / p->Iy : 0.0);
    Y[0] = Vn + dV, Y[1] = vx;
    if (dyn_vy) Y[2] += h * (w1 * L[1] + w2 * L[1]) / p->M;
    else Y[2] = p->ry * Y[0];
    if (dyn_spin) Y[3] += h * (w1 * L[3] + w2 * L[3]) / p->Iz;
    else Y[3] = p->rz * Y[0];
    *dv = (vx - vn) / h;
    return CF_OK;
}

/* RollingBody._step */
static int step(const cf_params *p, cf_state *y, double h, double Fx, double My) {
    if (lifted(p)) {
        double Y[4] = {y->Vx, y->vx, 0.0, 0.0}, dv;
        const double L[4] = {Fx, 0.0, My, 0.0};
        if (free_step(p, Y, h, L, 0, 0, &dv)) return CF_FALLBACK;
        y->Vx = Y[0], y->vx = Y[1], y->dv = dv;
        y->Tx = y->Ty = y->Mz = 0.0;
        y->out_sliding = saturated(p, y->Vx, y->vx);
        if (p->quasistationary) y->sliding = 1;
        return CF_OK;
    }
    int ok = admissible(p, Fx, My);
    if (p->quasistationary && !ok) y->sliding = 1;
    else if (p->m_slip == 0.0 && !ok) return CF_FALLBACK; /* Python raises */
    int algebraic = p->quasistationary && !y->sliding;
    double vn = y->vx, T[3];
    if ((p->sdirk ? sdirk_scalar : lobatto_scalar)(p, y, h, Fx, My, algebraic, T))
        return CF_FALLBACK;
    y->dv = (y->vx - vn) / h;
    double cap = p->mu * p->P;
    if (hypot(T[0], T[1]) > cap) {
        double r = cap / hypot(T[0], T[1]);
        T[0] *= r;
        T[1] *= r;
    }
    y->Tx = T[0];
    y->Ty = T[1];
    y->Mz = T[2];
    y->out_sliding = saturated(p, y->Vx, y->vx);
    if (p->quasistationary) { /* _update_regime */
        if (y->sliding) {
            if (!saturated(p, y->Vx, y->vx) && ok) y->sliding = 0;
        } else if (y->out_sliding) {
            y->sliding = 1;
        }
    }
    return CF_OK;
}

/* RollingBody.advance with held loads: h (s) in n equal steps; the quasistationary
 * method takes one step for the interval unless it ends in gross sliding. On
 * CF_FALLBACK *y is unchanged. */
static int state_finite(const cf_state *y) {
    const double v[7] = {y->Vx, y->vx, y->t, y->dv, y->Tx, y->Ty, y->Mz};
    return finite_all(v, 7);
}

int cf_advance(const cf_params *p, cf_state *y, double h, double Fx, double My, int n) {
    /* what no step can take: a step not in (0, inf), a non-finite load or state */
    if (!(h > 0.0 && h <= DBL_MAX) || n < 1 || !(h / n > 0.0) || !isfinite(Fx) ||
        !isfinite(My) || !state_finite(y))
        return CF_FALLBACK;
    cf_state w = *y;
    if (n > 1 && p->quasistationary && !w.sliding && admissible(p, Fx, My)) {
        if (step(p, &w, h, Fx, My) || !state_finite(&w)) return CF_FALLBACK;
        if (!w.sliding) {
            w.t = y->t + h;
            if (!isfinite(w.t)) return CF_FALLBACK;
            *y = w;
            return CF_OK;
        }
        w = *y;
    }
    double dt = h / n;
    /* a state that overflowed is not served: each step's end finite */
    for (int k = 0; k < n; k++)
        if (step(p, &w, dt, Fx, My) || !state_finite(&w)) return CF_FALLBACK;
    w.t = y->t + h;
    if (!isfinite(w.t)) return CF_FALLBACK;
    *y = w;
    return CF_OK;
}

/* ---- fmu/body_model.py + RollingBody.outputs: a communication step of the body ----- */

/* ---- the derived constants of layer.LayerContact and dynamics.Body ------------------ */
/* The thin-layer law at load P into p (mu, P, a1, creep_full_slip, beta_per_creep:
 * LayerContact.native_fields) and its lateral semi-axis a2 and peak pressure p0, Eq. (34):
 * delta = (P (k1 + k2)/pi)^(1/2) (Rx Ry)^(-1/4), a1 = (2 Rx delta)^(1/2), a2 = (2 Ry
 * delta)^(1/2), p0 = delta/(k1 + k2), creep_full_slip = 2 mu p0 (kb + ks)/a1. The
 * expressions of layer.py in its order: the same doubles (tests/test_native_fmu.py). */
void cf_layer_law(cf_params *p, double P, double Rx, double Ry, double k1, double k2,
                  double kb, double ks, double mu, double *a2, double *p0) {
    const double kn = k1 + k2;
    const double delta = sqrt(P * kn / M_PI) * pow(Rx * Ry, -0.25);
    const double a1 = sqrt(2.0 * Rx * delta);
    *a2 = sqrt(2.0 * Ry * delta);
    *p0 = delta / kn;
    /* P = 0 (lift-off): the limits, 0 and inf (LayerContact.creep_full_slip) */
    const double cfs = P == 0.0 ? 0.0 : p->beta_full_slip * mu * *p0 * (kb + ks) / a1;
    p->mu = mu;
    p->P = P;
    p->a1 = a1;
    p->creep_full_slip = cfs;
    p->beta_per_creep = P == 0.0 ? INFINITY : p->beta_full_slip / cfs;
}

/* The half-space creep-force table (halfspace/table.py, TableLaw) at load P and friction
 * mu into p (the patches of a table of several load nodes are blended at P where they
 * are read: patch, load_weights), with a2, p0:
 * the Hertz ellipse (halfspace/hertz.py: major = (3 P kfac/(2 pi Amin E*))^(1/3), minor =
 * major (1 - m)^(1/2), the eccentricity parameter m and kfac = (K - E)/m fixed by the
 * geometry, computed by the build), p0 = 3 P/(2 pi a1 a2), c = (a1 a2)^(1/2), xi_ref =
 * mu P/(G c^2), phi_ref = xi_ref/c, creep_full_slip = onset xi_ref (several nodes: the
 * nodes' onsets weighted at P, np.dot(w, onset)); the operations of hertz.py and table.py:
 * the same doubles. */
void cf_table_law(cf_params *p, double P, double mu, double kfac, double m, double Amin,
                  int a_le_b, double Estar, double G, double onset, double *a2, double *p0) {
    const double major = pow(3.0 * P * kfac / (2.0 * M_PI * Amin * Estar), 1.0 / 3.0);
    const double minor = major * sqrt(1.0 - m);
    const double a1 = a_le_b ? major : minor;
    *a2 = a_le_b ? minor : major;
    *p0 = P == 0.0 ? 0.0 : 3.0 * P / (2.0 * M_PI * a1 * *a2); /* P = 0: no contact */
    const double c = sqrt(a1 * *a2);
    const double xi_ref = P == 0.0 ? 0.0 : mu * P / (G * pow(c, 2.0));
    p->mu = mu;
    p->P = P;
    p->a1 = a1;
    p->c = c;
    p->xi_ref = xi_ref;
    p->phi_ref = P == 0.0 ? 0.0 : xi_ref / c;
    double on = 1.0 * onset; /* np.dot(w, onset): w = [1.0] for one node ... */
    if (p->n_loads > 1) {    /* ... else the nodes' weights at P */
        double w[CF_LOADS_MAX];
        const double *onsets = p->spline + 2 + (p->n_loads + p->spline_k + 1) +
                               (size_t)p->n_loads * p->n_loads;
        load_weights(p, P, w);
        on = 0.0;
        for (int j = 0; j < p->n_loads; j++) on += w[j] * onsets[j];
    }
    p->creep_full_slip = on * xi_ref;
}

/* dynamics.Body: A1 = M Rx^2/(M Rx^2 + Iy) (1 for Iy = 0), A2 = Iy/(M Rx^2 + Iy),
 * m_slip = M A2 (Eq. 23), in its operations (Rx**2 is pow there) */
void cf_body_inertia(cf_params *p, double M, double Rx, double Iy) {
    const double MR2 = M * pow(Rx, 2.0);
    p->A1 = Iy == 0.0 ? 1.0 : MR2 / (MR2 + Iy);
    p->A2 = Iy / (MR2 + Iy);
    p->m_slip = M * p->A2;
    p->Iy = Iy;
}

/* RollingBody.__init__'s forces at the initial state (vy = ry Vx, no spin) and the
 * regime flag, in y->Tx, Ty, Mz, out_sliding */
void cf_initial_forces(const cf_params *p, cf_state *y) {
    double T[3];
    law(p, y->vx, y->Vx, T);
    y->Tx = T[0], y->Ty = T[1], y->Mz = T[2];
    y->out_sliding = saturated(p, y->Vx, y->vx);
    y->sliding = 0;
    y->dv = 0.0;
}

/* LayerContact.adhesion_fraction, float path without spin */
static double adhesion_fraction(const cf_params *p, double vx, double vy, double Vx) {
    if (lifted(p)) return 0.0; /* no contact: nothing adheres */
    double s = hypot(vx, vy);
    if (s == 0.0) return 1.0;
    if (Vx == 0.0 || s * p->beta_per_creep >= p->beta_full_slip * fabs(Vx)) return 0.0;
    double b = s * p->beta_per_creep / fabs(Vx);
    double m = sqrt(1.0 - 0.25 * b * b);
    return (2.0 * asin(m) - b * m) / M_PI;
}

/* RollingBody.outputs() (kinematics and kinematics.contact_quantities) into b->out */
/* the kinematics, forces (Tx, Ty, Mz) and kinematics.contact_quantities of
 * RollingBody.outputs() into b->out, from the state (Vx, vx, Vy, Omega_z), for both paths
 * (the adhesion and the regime are each path's) */
static void kinematic_outputs(const cf_params *p, cf_body *b, double Vx, double vx, double Vy,
                              double Oz, double Tx, double Ty, double Mz) {
    double *o = b->out;
    o[O_VX] = Vx;
    o[O_VY] = Vy;
    o[O_OMEGA_Y] = (Vx - vx) / p->Rx;
    o[O_OMEGA_Z] = Oz;
    o[O_TX] = Tx;
    o[O_TY] = Ty;
    o[O_MZ] = Mz;
    o[O_VX_SLIP] = vx;
    o[O_VY_SLIP] = Vy;
    const double V = py_max(fabs(Vx), b->v_creep_floor);
    o[O_XI_X] = vx / V;
    o[O_XI_Y] = Vy / V;
    o[O_XI_SP] = Oz / V;
    o[O_A1] = p->a1;
    o[O_A2] = b->a2;
    o[O_P0] = b->p0;
}

void cf_body_outputs(const cf_params *p, const cf_state *y, cf_body *b) {
    double Vx = y->Vx, vx = y->vx;
    double Vy = p->ry * Vx, Omega_z = p->rz * Vx; /* _apply_ratios */
    double *o = b->out;
    kinematic_outputs(p, b, Vx, vx, Vy, Omega_z, y->Tx, y->Ty, y->Mz);
    if (p->law == LAW_TABLE) {
        double t[4];
        table_scalar(p, vx, Vy, Omega_z, Vx, t);
        o[O_ADHESION] = t[3];
    } else {
        o[O_ADHESION] = adhesion_fraction(p, vx, Vy, Vx);
    }
    o[O_REGIME] = saturated(p, Vx, vx) ? 1.0 : 0.0;
}


/* integrator.RollingBody's bound on |Fx_ex| (N; on |My_ex| times Rx) */
double cf_load_cap(const cf_params *p) { return CF_LOAD_LIMIT * p->mu * p->P; }

/* The loads and the step size: CF_OK, or the first check that fails in the order of
 * integrator.RollingBody (the load limit) and body_model.substeps, with *n the internal
 * steps ceil(h / h_max (1 - slack)), at least 1, at most max_substeps (also with
 * CF_STEP_CAPPED, after which a caller may take the step in those n) */
int cf_body_admit(const cf_params *p, const cf_body *b, double h, int *n) {
    *n = 1;
    if (b->P != p->P || !isfinite(b->P)) return CF_STEP_LAW;
    if (!cf_step_size_ok(h) || !(b->h_max > 0.0)) return CF_STEP_SIZE;
    const double cap = cf_load_cap(p); /* none at P = 0: free_step is exact */
    if (!(fabs(b->Fx_ex) <= cap) && !(lifted(p) && isfinite(b->Fx_ex))) return CF_STEP_FX_LIMIT;
    if (!(fabs(b->My_ex) <= cap * p->Rx) && !(lifted(p) && isfinite(b->My_ex)))
        return CF_STEP_MY_LIMIT;
    const double q = ceil(h / b->h_max * (1.0 - b->substep_slack));
    *n = q < b->max_substeps ? (q < 1.0 ? 1 : (int)q) : b->max_substeps;
    return q < b->max_substeps ? CF_OK : CF_STEP_CAPPED; /* NaN q: capped */
}


/* The index into out of the first output served (a bit per index) that is not finite,
 * or -1: slave._collect */
int cf_first_nonfinite(const double *out, unsigned long served) {
    for (int i = 0; i < N_OUT; i++)
        if ((served >> i & 1ul) && !isfinite(out[i])) return i;
    return -1;
}

/* The outputs of a step, checked as the Python adapter does: the body's speeds and
 * rates within their ranges (ranges.within_range, NaN beyond), then each output
 * served finite (slave._collect; served: a bit per index of out, whose order is the
 * variables'). CF_OK; CF_STEP_RANGE with *which the row of CF_RANGED; or
 * CF_STEP_NONFINITE with *which the index into out; the first that fails. */
int cf_body_out_check(const double *out, unsigned long served, int *which) {
    for (int k = 0; k < 4; k++)
        if (!(fabs(out[CF_RANGED[k].i]) <= CF_RANGED[k].bound)) {
            *which = k;
            return CF_STEP_RANGE;
        }
    return (*which = cf_first_nonfinite(out, served)) < 0 ? CF_OK : CF_STEP_NONFINITE;
}

/* ---- layer._Grid.march: the strip march of the spin law --------------------------- */

/* One rolling input (Vx != 0; layer.py keeps standstill in numpy): the march of
 * layer._Grid.march along each strip from the leading edge, with its operations in its
 * order: inc = (1/(|Vx| k)) dist ((vx - phi y) + i (vy - s phi mid)), trial = t + inc,
 * slip = |trial| > cap, t = trial min(1, cap / max(|trial|, tiny)). Writes the field
 * (tau: complex as re, im pairs; slip: 0/1 bytes; ny x nx, march order) where tau is
 * given, and always the resultants of _Grid.resultants, R = (Tx, Ty, Mz). |trial| is
 * sqrt(a^2 + b^2), within two roundings of numpy's complex abs (hypot where the squares
 * overflow), and the sums run in another order than numpy's: the two paths agree to
 * rounding, not bit for bit (tests/test_native.py). */
#define MARCH_LANES 8 /* strips marched together: their chains are independent */

/* The march's gain 1/(|Vx| k), bounded (layer._Grid.gain, docs/model.md): with L =
 * 2|x0| + |y0| >= every |y|, |mid| and dist of the grid (nx >= 2) and vb = max(|vx|,
 * |vy|, |phi| L), every increment gain dist (slip) is below 4 gain L vb; where gain L vb
 * would pass CF_INC_MAX (or is NaN: gain inf, no slip) the gain is CF_INC_MAX/(L vb) (0
 * without slip): continuous in Vx, and every node with a slip then slides (cap/|inc| <
 * 1e-280). *capped (may be NULL): 0 for 1/(|Vx| k), else 1 + the index (vx, vy, -, phi)
 * of vb's argument, for cf_march_jacobian; *vbp: vb. */
#define CF_INC_MAX 1e300
static double march_gain(const cf_strips *g, double vx, double vy, double Vx, double phi,
                         int *capped, double *vbp) {
    const double L = 2.0 * fabs(g->x[0]) + fabs(g->y[0]);
    const double gain = 1.0 / (fabs(Vx) * g->k);
    const double vb = fmax(fmax(fabs(vx), fabs(vy)), fabs(phi) * L);
    if (vbp) *vbp = vb;
    if (gain * L * vb <= CF_INC_MAX) {
        if (capped) *capped = 0;
        return gain;
    }
    if (capped) *capped = vb == fabs(vx) ? 1 : vb == fabs(vy) ? 2 : 4;
    return vb > 0.0 ? CF_INC_MAX / (L * vb) : 0.0;
}

/* march_one without spin, the resultants alone: the increments keep the direction
 * e = (vx, vy)/|v| on every strip, so tau = m e with the magnitude marched by itself,
 * m <- min(m + gain dist |v|, cap) (m (min(1, cap/tiny)) below tiny), and R = (e_x S,
 * e_y S, e_y Sx - e_x Sy) with S, Sx, Sy the sums of w m, w m sx, w m y. The same
 * resultants as march_one in exact arithmetic, without its square root and division
 * per node; the two agree to rounding (tests/test_native.py). */
static void march_straight(const cf_strips *g, double vx, double vy, double Vx, double R[3]) {
    const int ny = g->ny, nx = g->nx;
    const double s = Vx > 0.0 ? 1.0 : -1.0, speed = hypot(vx, vy);
    R[0] = R[1] = R[2] = 0.0;
    if (!(speed > 0.0)) return; /* no slip: no increment, no traction */
    const double gain = speed * march_gain(g, vx, vy, Vx, 0.0, NULL, NULL); /* < 2 inc max/L */
    double S = 0.0, Sx = 0.0, Sy = 0.0;
    for (int i = 0; i < ny; i++) {
        double m = 0.0, si = 0.0, sx = 0.0;
        for (int j = 0; j < nx; j++) {
            const size_t e = (size_t)i * nx + j;
            const double mag = m + gain * g->dist[e], c = g->cap[e];
            m = mag >= g->tiny ? (mag < c ? mag : c) : mag * (c < g->tiny ? c / g->tiny : 1.0);
            si += g->w[e] * m;
            sx += g->w[e] * m * (-s * g->x[j]);
        }
        S += si;
        Sx += sx;
        Sy += si * g->y[i];
    }
    R[0] = vx / speed * S;
    R[1] = vy / speed * S;
    R[2] = vy / speed * Sx - vx / speed * Sy;
}

/* The march is homogeneous of degree 0 in (vx, vy, Vx, phi): scaled by the power of two
 * that brings the largest of them into [0.5, 1) when it is below 0.5 or above 2^512
 * (exact: the same doubles wherever the unscaled march neither overflows nor leaves the
 * normal range), velocities of any finite size march without 1/(|Vx| k) or the bounded
 * gain overflowing (Vx = 1e-300 with a spin of 1e-300 rad/s gave NaN).
 * layer._Grid._march_numpy alike. */
static int march_scale(double vx, double vy, double Vx, double phi) {
    const double m = fmax(fmax(fabs(vx), fabs(vy)), fmax(fabs(Vx), fabs(phi)));
    int e = 0;
    if (m > 0.0 && isfinite(m)) frexp(m, &e);
    /* up from below 0.5 (exact, subnormals included); down only from above 2^512, where
     * the march overflowed before (down from smaller sizes would round subnormals away) */
    return e < 0 || e > 512 ? -e : 0;
}

static void march_one(const cf_strips *g, double vx, double vy, double Vx, double phi,
                      double *tau, unsigned char *slip, double R[3]) {
    if (g == NULL) { /* callers check; never a NULL grid dereferenced */
        R[0] = R[1] = R[2] = NAN;
        return;
    }
    const int e = march_scale(vx, vy, Vx, phi);
    vx = ldexp(vx, e);
    vy = ldexp(vy, e);
    Vx = ldexp(Vx, e);
    phi = ldexp(phi, e);
    if (phi == 0.0 && tau == NULL) {
        march_straight(g, vx, vy, Vx, R);
        return;
    }
    const int ny = g->ny, nx = g->nx;
    const double s = Vx > 0.0 ? 1.0 : -1.0;
    const double gain = march_gain(g, vx, vy, Vx, phi, NULL, NULL);
    const double sphi = s * phi;
    double Tr = 0.0, Ti = 0.0, M = 0.0;
    /* Each strip's march is one chain of dependent operations (a square root and a
     * division per node); MARCH_LANES strips side by side let the processor overlap
     * them. The resultants are summed per strip, then over the strips in order. */
    for (int i0 = 0; i0 < ny; i0 += MARCH_LANES) {
        const int m = ny - i0 < MARCH_LANES ? ny - i0 : MARCH_LANES;
        double tr[MARCH_LANES] = {0.0}, ti[MARCH_LANES] = {0.0}, re[MARCH_LANES];
        double sr[MARCH_LANES] = {0.0}, si[MARCH_LANES] = {0.0}, sm[MARCH_LANES] = {0.0};
        for (int l = 0; l < m; l++) re[l] = vx - phi * g->y[i0 + l];
        for (int j = 0; j < nx; j++) {
            const double sx = -s * g->x[j];
            for (int l = 0; l < m; l++) {
                const size_t e = (size_t)(i0 + l) * nx + j;
                const double gd = gain * g->dist[e], c = g->cap[e];
                const double a = tr[l] + gd * re[l], b = ti[l] + gd * (vy - sphi * g->mid[e]);
                double mag = sqrt(a * a + b * b); /* hypot's cost, 5x, only on overflow */
                if (!(mag <= DBL_MAX)) mag = hypot(a, b);
                const double q = c / (g->tiny > mag ? g->tiny : mag);
                const double f = q < 1.0 ? q : 1.0;
                tr[l] = a * f;
                ti[l] = b * f;
                if (tau) {
                    tau[2 * e] = tr[l];
                    tau[2 * e + 1] = ti[l];
                    slip[e] = mag > c;
                }
                sr[l] += g->w[e] * tr[l];
                si[l] += g->w[e] * ti[l];
                sm[l] += g->w[e] * (sx * ti[l] - g->y[i0 + l] * tr[l]);
            }
        }
        for (int l = 0; l < m; l++) {
            Tr += sr[l];
            Ti += si[l];
            M += sm[l];
        }
    }
    R[0] = Tr;
    R[1] = Ti;
    R[2] = M;
}

/* march_one for n inputs: the fields tau and slip, (n x ny x nx). */
/* CF_FALLBACK (the fields then hold NaN for those inputs) where an input is not finite,
 * Vx is 0 (standstill is numpy's) or a traction overflowed. */
int cf_strip_march(const cf_strips *g, int n, const double *vx, const double *vy,
                   const double *Vx, const double *phi, double *tau, unsigned char *slip) {
    if (g == NULL || g->ny < 0 || g->nx < 0) return CF_FALLBACK;
    const size_t field = (size_t)g->ny * g->nx;
    int status = CF_OK;
    for (int k = 0; k < n; k++) {
        double R[3], *t = tau + 2 * (size_t)k * field;
        const double in[4] = {vx[k], vy[k], Vx[k], phi[k]};
        if (!finite_all(in, 4) || Vx[k] == 0.0) {
            for (size_t e = 0; e < field; e++) t[2 * e] = t[2 * e + 1] = NAN, slip[k * field + e] = 1;
            status = CF_FALLBACK;
            continue;
        }
        march_one(g, vx[k], vy[k], Vx[k], phi[k], t, slip + (size_t)k * field, R);
        if (!finite_all(t, (int)(2 * field)) || !finite_all(R, 3)) status = CF_FALLBACK;
    }
    return status;
}

/* LayerContact.forces for n rolling inputs: the closed form without spin (forces above,
 * LayerContact._forces_scalar) plus, where phi != 0, the strip march with the spin less
 * the march without it. out: (Tx, Ty, Mz) per input. */
int cf_layer_forces(const cf_params *p, const cf_strips *g, int n, const double *vx,
                    const double *vy, const double *phi, const double *Vx, double *out) {
    int status = CF_OK;
    for (int k = 0; k < n; k++) {
        double *T = out + 3 * (size_t)k;
        const double in[4] = {vx[k], vy[k], phi[k], Vx[k]};
        /* CF_FALLBACK, NaN forces: a non-finite input, standstill, spin without a grid */
        if (!finite_all(in, 4) || Vx[k] == 0.0 || (phi[k] != 0.0 && g == NULL && !lifted(p))) {
            T[0] = T[1] = T[2] = NAN;
            status = CF_FALLBACK;
            continue;
        }
        if (lifted(p)) { /* no contact */
            T[0] = T[1] = T[2] = 0.0;
            continue;
        }
        forces(p, vx[k], vy[k], Vx[k], T);
        if (phi[k] != 0.0) {
            double with[3], without[3];
            march_one(g, vx[k], vy[k], Vx[k], phi[k], NULL, NULL, with);
            march_one(g, vx[k], vy[k], Vx[k], 0.0, NULL, NULL, without);
            for (int c = 0; c < 3; c++) T[c] += with[c] - without[c];
        }
        if (!finite_all(T, 3)) status = CF_FALLBACK;
    }
    return status;
}

/* ---- the native FMU's contact mode with a spin input ------------------------------- */
/* layer._Grid._march_numpy at standstill (Vx = 0; no rolling: every point slides, Eq. 5):
 * tau = mu p v/|v| with the slip v = (vx - phi y) + i (vy + phi x) of Eq. (3) at each
 * node (x in column order), 0 where v = 0; R = (Tx, Ty, Mz) of _Grid.resultants. numpy
 * sums in another order: the two agree to rounding. */
void cf_march_standstill(const cf_strips *g, double vx, double vy, double phi, double R[3]) {
    double Tr = 0.0, Ti = 0.0, M = 0.0;
    for (int i = 0; i < g->ny; i++)
        for (int j = 0; j < g->nx; j++) {
            const size_t e = (size_t)i * g->nx + j;
            const double a = vx - phi * g->y[i], b = vy + phi * g->x[j], mag = hypot(a, b);
            if (!(mag > 0.0)) continue;
            const double tr = g->cap[e] * a / mag, ti = g->cap[e] * b / mag;
            Tr += g->w[e] * tr;
            Ti += g->w[e] * ti;
            M += g->w[e] * (g->x[j] * ti - g->y[i] * tr);
        }
    R[0] = Tr, R[1] = Ti, R[2] = M;
}

/* The forward-mode derivative of march_one (rolling, Vx != 0) for one input: D (3 x 4,
 * row major) = d(Tx, Ty, Mz)/d(vx, vy, Vx, phi) of its resultants, through each node's
 * operations in march_one's order (the same doubles decide each node's branch). The
 * increment inc = gd ((vx - phi y) + i (vy - s phi mid)), gd = dist/(|Vx| k), is linear
 * in vx, vy, phi and goes as 1/|Vx|: d inc = gd (dvx - y dphi) + i gd (dvy - s mid dphi)
 * - inc dVx/Vx. A node in adhesion (|trial| <= cap) passes dtrial on; one in slip,
 * t = cap trial/|trial|, passes cap (dtrial - e (e . dtrial))/|trial| with e =
 * trial/|trial| (the projection's derivative); below tiny the factor cap/tiny is a
 * constant. At a node exactly on the boundary (|trial| = cap) it takes the adhesion
 * side: a one-sided derivative, as everywhere the march has a kink. */
void cf_march_jacobian(const cf_strips *g, double vx, double vy, double Vx, double phi,
                       double D[12]) {
    const int ny = g->ny, nx = g->nx;
    const double s = Vx > 0.0 ? 1.0 : -1.0;
    int capped;
    double vb;
    const double gain = march_gain(g, vx, vy, Vx, phi, &capped, &vb);
    const double L = 2.0 * fabs(g->x[0]) + fabs(g->y[0]);
    /* a bounded gain, CF_INC_MAX/(L vb), varies with vb's argument v_c and not with Vx:
     * d gain = -gain sign(v_c) (L for phi) dv_c/vb */
    const int kc = capped ? capped - 1 : 2;
    const double dlog = !capped || !(vb > 0.0) ? 0.0
                        : kc == 3 ? -(phi > 0.0 ? L : -L) / vb
                                  : -((kc == 0 ? vx : vy) > 0.0 ? 1.0 : -1.0) / vb;
    const int kg = capped ? kc : 2;                  /* the column the gain varies with */
    const double lam = capped ? dlog : -1.0 / Vx;    /* d gain/gain in that column */
    const double sphi = s * phi;
    for (int k = 0; k < 12; k++) D[k] = 0.0;
    for (int i = 0; i < ny; i++) {
        const double yi = g->y[i], re = vx - phi * yi;
        double tr = 0.0, ti = 0.0, dr[4] = {0.0}, di[4] = {0.0};
        for (int j = 0; j < nx; j++) {
            const size_t e = (size_t)i * nx + j;
            const double gd = gain * g->dist[e], c = g->cap[e], im = vy - sphi * g->mid[e];
            const double a = tr + gd * re, b = ti + gd * im; /* march_one's trial */
            double mag = sqrt(a * a + b * b);
            if (!(mag <= DBL_MAX)) mag = hypot(a, b);
            const double q = c / (g->tiny > mag ? g->tiny : mag);
            /* the increment's derivative, added to the carried one: dtrial (the gain's
             * part, lam inc in column kg, below: it depends on the branch) */
            dr[0] += gd, di[1] += gd;
            dr[3] -= gd * yi, di[3] -= gd * s * g->mid[e];
            if (q < 1.0 && !(g->tiny > mag)) { /* slip: the projection on |tau| = cap */
                const double ea = a / mag, eb = b / mag;
                for (int k = 0; k < 4; k++) {
                    const double along = ea * dr[k] + eb * di[k];
                    dr[k] = q * (dr[k] - ea * along);
                    di[k] = q * (di[k] - eb * along);
                }
                /* lam inc = lam (trial - t_prev): across e it is -lam t_prev's part
                 * across e, exactly; taken so, not as lam |inc| (up to 1e300/|Vx|) less
                 * its part along e, which cancels to nothing but rounding */
                const double along = ea * tr + eb * ti, pa = tr - ea * along, pb = ti - eb * along;
                dr[kg] -= (q * pa) * lam, di[kg] -= (q * pb) * lam;
            } else {
                if (!capped)
                    dr[2] -= gd * re / Vx, di[2] -= gd * im / Vx;
                else
                    dr[kc] += gd * re * dlog, di[kc] += gd * im * dlog;
                if (q < 1.0) /* below tiny: the constant factor cap/tiny */
                    for (int k = 0; k < 4; k++) dr[k] *= q, di[k] *= q;
            }
            const double f = q < 1.0 ? q : 1.0;
            tr = a * f;
            ti = b * f;
            const double w = g->w[e], sx = -s * g->x[j];
            for (int k = 0; k < 4; k++) {
                D[k] += w * dr[k];
                D[4 + k] += w * di[k];
                D[8 + k] += w * (sx * di[k] - yi * dr[k]);
            }
        }
    }
}

/* ---- integrator.RollingBody._lobatto_vector: Vy and/or Omega_z as stage unknowns ---- */
/* The Lobatto IIIC step with n = 2 or 3 unknowns u = (vx[, Vy][, Omega_z]) and its
 * Newton iteration (solvers.newton with the block Jacobian of _lobatto_vector), for the
 * thin-layer law (spin through the strip march) and the creep-force table; in the
 * quasistationary method, while rolling, the algebraic stage T(u2) = F2 (n x n, the
 * forward-difference Jacobian of solvers.newton) and the regime of RollingBody._step;
 * for both, the Newton starts of integrator._newton_from.
 * The Newton systems are solved by Gaussian elimination with partial pivoting
 * (LAPACK's, in numpy, runs its operations in another order): the two paths agree to
 * the stage tolerance, not bit for bit (tests/test_native.py). What this path leaves to
 * Python (CF_FALLBACK, state untouched): a singular Newton matrix or no convergence in
 * newton_iterations from every start (Python then calls scipy's hybrid method), and in
 * the full method eta = inf with loads beyond mu P (Python raises). */

/* the law at state y = (Vx, vx, Vy, Omega_z) and speed V; the thin-layer law as
 * cf_layer_forces */
static void law_at(const cf_params *p, const double y[4], double V, double T[3],
                   march_cache *c) {
    /* a non-finite state (a step that overflowed) has no forces: NaN, which every
     * caller's check turns into "not covered"; a spin without a spin grid likewise */
    const cf_strips *g = (const cf_strips *)p->strips;
    if (!finite_all(y, 4) || !isfinite(V) ||
        (p->law == LAW_LAYER && y[3] != 0.0 && !g && !lifted(p))) {
        T[0] = T[1] = T[2] = NAN;
        return;
    }
    if (lifted(p)) { /* no contact */
        T[0] = T[1] = T[2] = 0.0;
        return;
    }
    if (p->law == LAW_TABLE) {
        double o[4];
        table_scalar(p, y[1], y[2], y[3], V, o);
        T[0] = o[0], T[1] = o[1], T[2] = o[2];
        return;
    }
    forces(p, y[1], y[2], V, T);
    if (y[3] == 0.0) return;
    double with[3];
    march_one(g, y[1], y[2], V, y[3], NULL, NULL, with);
    if (!(c->valid && c->vx == y[1] && c->vy == y[2] && c->V == V)) {
        march_one(g, y[1], y[2], V, 0.0, NULL, NULL, c->R);
        c->valid = 1, c->vx = y[1], c->vy = y[2], c->V = V;
    }
    for (int k = 0; k < 3; k++) T[k] += with[k] - c->R[k];
}

/* RollingBody._forces at one state: the law at Vx, or for |Vx| < v_standstill the blend
 * of the law at +v_standstill and -v_standstill (integrator.forces_at_rest) */
static void forces_at(const cf_params *p, const double y[4], double T[3], march_cache *c) {
    if (fabs(y[0]) >= p->v_standstill) {
        law_at(p, y, y[0], T, c);
        return;
    }
    double Tp[3], Tm[3], w = 0.5 * (1.0 + y[0] / p->v_standstill);
    law_at(p, y, p->v_standstill, Tp, c);
    law_at(p, y, -p->v_standstill, Tm, c);
    for (int k = 0; k < 3; k++) T[k] = w * Tp[k] + (1.0 - w) * Tm[k];
}

typedef struct {
    const cf_params *p;
    int n, act[3], algebraic; /* algebraic: the quasistationary stage T(u) = F2 */
    double y[4], un[3], F1[3], F2[3], m[3], Vb[2], h;
    march_cache *cache;
} vstage;

/* _lobatto_vector's states(U, stage): the state at the stage unknowns U */
static void vstate_at(const vstage *s, const double *U, int stage, double Y[4]) {
    for (int i = 0; i < 4; i++) Y[i] = s->y[i];
    for (int i = 0; i < s->n; i++) Y[s->act[i] + 1] = U[i];
    Y[0] = s->Vb[stage] + (s->m[0] / s->p->M) * (U[0] - s->un[0]);
    if (!s->p->dyn_vy) Y[2] = s->p->ry * Y[0]; /* BodyState._apply_ratios */
    if (!s->p->dyn_spin) Y[3] = s->p->rz * Y[0];
}

/* T[act] at stage `stage` for unknowns U */
static void stage_forces(const vstage *s, const double *U, int stage, double *Ta) {
    double Y[4], T[3];
    vstate_at(s, U, stage, Y);
    forces_at(s->p, Y, T, s->cache);
    for (int i = 0; i < s->n; i++) Ta[i] = T[s->act[i]];
}

/* _lobatto_vector's residuals at UU = (u1, u2); the stage forces into T1, T2. The
 * algebraic stage: UU = u2 alone, R = T(u2) - F2 (T1 untouched). */
static void vresiduals(const vstage *s, const double *UU, double *R, double *T1, double *T2) {
    const int n = s->n;
    if (s->algebraic) {
        stage_forces(s, UU, 1, T2);
        for (int i = 0; i < n; i++) R[i] = T2[i] - s->F2[i];
        return;
    }
    const double *U1 = UU, *U2 = UU + n;
    stage_forces(s, U1, 0, T1);
    stage_forces(s, U2, 1, T2);
    for (int i = 0; i < n; i++) {
        R[i] = s->m[i] * (U1[i] + U2[i] - 2.0 * s->un[i]) / s->h + T1[i] - s->F1[i];
        R[n + i] = s->m[i] * (U2[i] - U1[i]) / s->h + T2[i] - s->F2[i];
    }
}

/* _lobatto_vector's jacobian: the mass terms exactly, T(u_i) by forward differences in
 * stage i's unknowns, J (2n x 2n, row major). The algebraic stage: solvers.newton's
 * forward differences of the residuals R (n x n). */
static void vjacobian(const vstage *s, const double *UU, const double *du, const double *T1,
                      const double *T2, const double *R, double *J) {
    const int n = s->n, N = 2 * n;
    if (s->algebraic) {
        for (int j = 0; j < n; j++) {
            double U[3], Tp[3];
            for (int i = 0; i < n; i++) U[i] = UU[i];
            U[j] += du[j];
            stage_forces(s, U, 1, Tp);
            for (int i = 0; i < n; i++) J[i * n + j] = ((Tp[i] - s->F2[i]) - R[i]) / du[j];
        }
        return;
    }
    for (int k = 0; k < N * N; k++) J[k] = 0.0;
    for (int st = 0; st < 2; st++) {
        const double *T = st == 0 ? T1 : T2;
        for (int j = 0; j < n; j++) {
            double U[3], Tp[3];
            for (int i = 0; i < n; i++) U[i] = UU[st * n + i];
            U[j] += du[st * n + j];
            stage_forces(s, U, st, Tp);
            for (int i = 0; i < n; i++)
                J[(st * n + i) * N + st * n + j] = (Tp[i] - T[i]) / du[st * n + j];
        }
    }
    for (int i = 0; i < n; i++) {
        double D = s->m[i] / s->h;
        J[i * N + i] = D + J[i * N + i];
        J[i * N + n + i] = D;
        J[(n + i) * N + i] = -D;
        J[(n + i) * N + n + i] = D + J[(n + i) * N + n + i];
    }
}

/* solve J x = b (N <= 6) by Gaussian elimination with partial pivoting; 1 if singular */
static int solve_small(int N, double *J, double *b) {
    for (int c = 0; c < N; c++) {
        int piv = c;
        for (int r = c + 1; r < N; r++)
            if (fabs(J[r * N + c]) > fabs(J[piv * N + c])) piv = r;
        if (J[piv * N + c] == 0.0 || !isfinite(J[piv * N + c])) return 1;
        if (piv != c) {
            for (int k = 0; k < N; k++) {
                double t = J[c * N + k];
                J[c * N + k] = J[piv * N + k];
                J[piv * N + k] = t;
            }
            double t = b[c];
            b[c] = b[piv];
            b[piv] = t;
        }
        for (int r = c + 1; r < N; r++) {
            double f = J[r * N + c] / J[c * N + c];
            for (int k = c; k < N; k++) J[r * N + k] -= f * J[c * N + k];
            b[r] -= f * b[c];
        }
    }
    for (int c = N - 1; c >= 0; c--) {
        double v = b[c];
        for (int k = c + 1; k < N; k++) v -= J[c * N + k] * b[k];
        b[c] = v / J[c * N + c];
    }
    return 0;
}

static double norm2(int N, const double *r) {
    double q = 0.0;
    for (int i = 0; i < N; i++) q += r[i] * r[i];
    return sqrt(q);
}

/* every |step_i| <= rtol (|u_i| + scale_i): solvers.newton's stopping rule on a full step */
static int small_step(int n, const double *step, const double *u, const double *scale,
                      double rtol) {
    for (int i = 0; i < n; i++)
        if (!(fabs(step[i]) <= rtol * (fabs(u[i]) + scale[i]))) return 0;
    return 1;
}

/* solvers.newton on the Lobatto stage system (u0 = (un, un)) with its memo: Jk (valid if
 * *kept) the Jacobian kept from the last step, replaced by the last one formed;
 * CF_FALLBACK where Python goes on with scipy's hybrid method */
static int vnewton(const vstage *s, const double *scale, double *u, double *Jk, int *kept_in) {
    const cf_params *p = s->p;
    const int N = s->algebraic ? s->n : 2 * s->n;
    double r[6], T1[3] = {0.0}, T2[3], J[36], step[6], du[6], un[6], rn[6], T1n[3] = {0.0}, T2n[3];
    double norm = 0.0;
    int have = *kept_in;
    vresiduals(s, u, r, T1, T2);
    for (int it = 0; it < p->newton_iterations; it++) {
        int kept = have;
        if (!kept) {
            for (int i = 0; i < N; i++) du[i] = p->fd_step * (fabs(u[i]) + scale[i]);
            vjacobian(s, u, du, T1, T2, r, Jk);
            have = *kept_in = 1;
        }
        for (int k = 0; k < N * N; k++) J[k] = Jk[k]; /* solve_small overwrites */
        for (int i = 0; i < N; i++) step[i] = -r[i];
        if (solve_small(N, J, step)) {
            if (!kept) return CF_FALLBACK;
            have = 0;
            continue;
        }
        double lam = 1.0, norm0 = norm2(N, r);
        for (;;) {
            for (int i = 0; i < N; i++) un[i] = u[i] + lam * step[i];
            vresiduals(s, un, rn, T1n, T2n);
            norm = norm2(N, rn);
            if (kept || norm < norm0 || lam < p->line_search_min) break;
            lam *= 0.5;
        }
        if (!kept && !(norm < norm0) && !small_step(N, step, u, scale, p->solve_rtol))
            return CF_FALLBACK; /* no descent along a step that is not small (solvers.newton) */
        if (kept && !(norm <= p->contraction_max * norm0)) {
            have = 0; /* the step is dropped; a new Jacobian at u */
            continue;
        }
        int done = 1;
        for (int i = 0; i < N; i++) {
            u[i] = un[i];
            r[i] = rn[i];
            if (!(fabs(lam * step[i]) <= p->solve_rtol * (fabs(u[i]) + scale[i]))) done = 0;
        }
        for (int i = 0; i < s->n; i++) T1[i] = T1n[i], T2[i] = T2n[i];
        if (done) return CF_OK;
        if (kept && norm > p->contraction_fast * norm0) have = 0; /* slow: renewed */
    }
    return CF_FALLBACK;
}

/* integrator._signed: V with its magnitude at least v_scale_floor (0 taken as positive) */
static double signed_floor(const cf_params *p, double V) {
    return V >= 0.0 ? py_max(fabs(V), p->v_scale_floor) : -py_max(fabs(V), p->v_scale_floor);
}

/* RollingBody._creep_start: the last state's creepages at the stage's speed V, the
 * slip (vx[, Vy]) pulled back to half the onset of full slip where it is beyond it */
static void creep_start(const vstage *s, double V, double *u) {
    const cf_params *p = s->p;
    double ratio = signed_floor(p, V) / signed_floor(p, s->y[0]), Y[4];
    for (int i = 0; i < 4; i++) Y[i] = s->y[i];
    Y[0] = V;
    for (int i = 0; i < s->n; i++) Y[s->act[i] + 1] = u[i] = s->un[i] * ratio;
    if (!p->dyn_vy) Y[2] = p->ry * Y[0]; /* BodyState._apply_ratios */
    if (!p->dyn_spin) Y[3] = p->rz * Y[0];
    double slip = hypot(Y[1], Y[2]);
    double onset = p->creep_full_slip * py_max(fabs(V), p->v_scale_floor);
    if (slip >= onset && slip > 0.0) {
        double k = 0.5 * onset / slip;
        for (int i = 0; i < s->n; i++)
            if (s->act[i] < 2) u[i] *= k; /* vx, Vy; not the spin */
    }
}

/* Eq. (27) for the vector path (RollingBody._admissible): the demanded (Tx, Ty) inside
 * the capacity mu P */
static int vadmissible(const cf_params *p, const double L[4]) {
    double cap = p->mu * p->P * (1.0 - p->capacity_margin);
    return hypot(target_x(p, L[0], L[2]), p->dyn_vy ? L[1] : 0.0) < cap;
}

/* the end of RollingBody._step on the vector path: the step's state Y and forces T into
 * w, with _dv, the force's rounding at mu P and the regime flag */
static int vcommit(const cf_params *p, cf_vstate *w, double h, const double Y[4], double T[3]) {
    w->dv = (Y[1] - w->vx) / h;
    double cap = p->mu * p->P;
    if (hypot(T[0], T[1]) > cap) {
        double r = cap / hypot(T[0], T[1]);
        T[0] *= r;
        T[1] *= r;
    }
    w->Vx = Y[0], w->vx = Y[1], w->Vy = Y[2], w->Oz = Y[3];
    w->Tx = T[0], w->Ty = T[1], w->Mz = T[2];
    w->out_sliding = full_slip(p, Y[1], Y[2], Y[0]);
    return CF_OK;
}

/* ---- integrator.RollingBody._sdirk_vector: SDIRK2 with Vy and/or Omega_z as unknowns -- */
/* A stage of SDIRK2 in a vstage: y the explicit part y_hat, un its unknowns u_hat, Vb[1]
 * the stage's speed without the slip, F2 the targets, h the step times gamma. Its
 * residuals m (u - u_hat)/(h gamma) + T(u) - F (n of them; the quasistationary stage with
 * the masses zero), the stage forces into T. */
static void sresiduals(const vstage *s, const double *U, double *R, double *T) {
    stage_forces(s, U, 1, T);
    for (int i = 0; i < s->n; i++) R[i] = s->m[i] * (U[i] - s->un[i]) / s->h + T[i] - s->F2[i];
}

/* solvers.newton without a memo (as _sdirk_vector calls it): the forward-difference
 * Jacobian of the residuals formed anew at every iterate, backtracking on |r|;
 * CF_FALLBACK where Python goes on with scipy's hybrid method (a singular matrix, no
 * convergence in newton_iterations) */
static int snewton(const vstage *s, const double *scale, double *u) {
    const cf_params *p = s->p;
    const int n = s->n;
    double r[3], T[3], J[9], du[3], step[3], un[3], rn[3], U[3], Rp[3];
    sresiduals(s, u, r, T);
    for (int it = 0; it < p->newton_iterations; it++) {
        for (int j = 0; j < n; j++) du[j] = p->fd_step * (fabs(u[j]) + scale[j]);
        for (int j = 0; j < n; j++) {
            for (int i = 0; i < n; i++) U[i] = u[i];
            U[j] = u[j] + du[j];
            sresiduals(s, U, Rp, T);
            for (int i = 0; i < n; i++) J[i * n + j] = (Rp[i] - r[i]) / du[j];
        }
        for (int i = 0; i < n; i++) step[i] = -r[i];
        if (solve_small(n, J, step)) return CF_FALLBACK;
        double lam = 1.0, norm0 = norm2(n, r), norm;
        for (;;) {
            for (int i = 0; i < n; i++) un[i] = u[i] + lam * step[i];
            sresiduals(s, un, rn, T);
            norm = norm2(n, rn);
            if (norm < norm0 || lam < p->line_search_min) break;
            lam *= 0.5;
        }
        if (!(norm < norm0) && !small_step(n, step, u, scale, p->solve_rtol))
            return CF_FALLBACK; /* no descent along a step that is not small (solvers.newton) */
        int done = 1;
        for (int i = 0; i < n; i++) {
            u[i] = un[i];
            r[i] = rn[i];
            if (!(fabs(lam * step[i]) <= p->solve_rtol * (fabs(u[i]) + scale[i]))) done = 0;
        }
        if (done) return CF_OK;
    }
    return CF_FALLBACK;
}

/* RollingBody._step with _sdirk_vector, held loads L = (Fx_ex, Fy_ex, My_ex, Mz_ex): the
 * two stages in turn, each from its explicit part, y_hat_2 = y_n + (1 - gamma)/gamma
 * (Y1 - y_n) (an unknown without mass, Y1's: no memory there); the forces
 * close the last stage's balance. The kept Newton matrix is Lobatto's alone. */
static int sdirk_vstep(const cf_params *p, cf_vstate *w, double h, const double L[4],
                       int algebraic) {
    const double Fx = L[0], Fy = L[1], My = L[2], Mz = L[3];
    if (p->m_slip == 0.0 && !p->quasistationary && !vadmissible(p, L)) return CF_FALLBACK;
    march_cache cache = {0, 0.0, 0.0, 0.0, {0.0, 0.0, 0.0}};
    const double g = p->gamma, hg = h * g, yn[4] = {w->Vx, w->vx, w->Vy, w->Oz};
    vstage s = {p, 0, {0, 0, 0}, 0, {yn[0], yn[1], yn[2], yn[3]}, {0}, {0}, {0}, {0},
                {0}, hg, &cache};
    const double F[3] = {target_x(p, Fx, My), Fy, Mz}, m[3] = {p->m_slip, p->M, p->Iz};
    s.act[s.n++] = 0;
    if (p->dyn_vy) s.act[s.n++] = 1;
    if (p->dyn_spin) s.act[s.n++] = 2;
    for (int i = 0; i < s.n; i++) {
        s.F2[i] = F[s.act[i]];
        s.m[i] = algebraic ? 0.0 : m[s.act[i]];
    }
    const double G = drive(p, Fx, My);
    double u[3], Y[4], T[3];
    for (int st = 0; st < 2; st++) {
        s.Vb[1] = s.y[0] + hg * G / p->M;
        const double v = p->creep_full_slip * py_max(fabs(s.Vb[1]), p->v_scale_floor);
        const double sc[3] = {v, v, v / p->a1};
        double scale[3];
        for (int i = 0; i < s.n; i++) {
            u[i] = s.un[i] = s.y[s.act[i] + 1];
            scale[i] = sc[s.act[i]];
        }
        /* from the explicit part; else from its creepages pulled back, then without slip
         * (RollingBody._sdirk_vector's starts) */
        if (snewton(&s, scale, u)) {
            creep_start(&s, s.Vb[1], u);
            if (snewton(&s, scale, u)) {
                creep_start(&s, s.Vb[1], u);
                for (int i = 0; i < s.n; i++)
                    if (s.act[i] < 2) u[i] = 0.0; /* _no_slip: vx, Vy; not the spin */
                if (snewton(&s, scale, u)) return CF_FALLBACK;
            }
        }
        vstate_at(&s, u, 1, Y);
        if (st == 0) {
            for (int k = 0; k < 4; k++) s.y[k] = yn[k] + (1.0 - g) / g * (Y[k] - yn[k]);
            for (int i = 0; i < s.n; i++) /* no memory where an unknown has no mass */
                if (s.m[i] == 0.0) s.y[s.act[i] + 1] = Y[s.act[i] + 1];
        }
    }
    forces_at(p, Y, T, &cache);
    for (int i = 0; i < s.n; i++) T[s.act[i]] = s.F2[i] - s.m[i] * (u[i] - s.un[i]) / hg;
    return vcommit(p, w, h, Y, T);
}

/* RollingBody._step with _lobatto_vector, held loads L = (Fx_ex, Fy_ex, My_ex, Mz_ex):
 * the Lobatto stages, or (algebraic) the quasistationary stage T(u2) = F2 with the
 * masses of the unknowns zero (its Newton matrix kept under p->algebraic_key) */
static int vstep(const cf_params *p, cf_vstate *w, double h, const double L[4], int algebraic) {
    if (lifted(p)) { /* RollingBody._free_step */
        double Y[4] = {w->Vx, w->vx, w->Vy, w->Oz}, dv;
        if (free_step(p, Y, h, L, p->dyn_vy, p->dyn_spin, &dv)) return CF_FALLBACK;
        w->Vx = Y[0], w->vx = Y[1], w->Vy = Y[2], w->Oz = Y[3], w->dv = dv;
        w->Tx = w->Ty = w->Mz = 0.0;
        w->out_sliding = full_slip(p, Y[1], Y[2], Y[0]);
        if (p->quasistationary) w->sliding = 1;
        return CF_OK;
    }
    if (p->sdirk) return sdirk_vstep(p, w, h, L, algebraic);
    const double Fx = L[0], Fy = L[1], My = L[2], Mz = L[3];
    march_cache cache = {0, 0.0, 0.0, 0.0, {0.0, 0.0, 0.0}};
    vstage s = {p, 0, {0, 0, 0}, algebraic, {w->Vx, w->vx, w->Vy, w->Oz}, {0}, {0}, {0}, {0},
                {0}, h, &cache};
    double F[3] = {target_x(p, Fx, My), Fy, Mz}, m[3] = {p->m_slip, p->M, p->Iz};
    s.act[s.n++] = 0;
    if (p->dyn_vy) s.act[s.n++] = 1;
    if (p->dyn_spin) s.act[s.n++] = 2;
    /* _step: the full method raises without a slip mass beyond the capacity (Python
     * does); the quasistationary one slides there (qs_step) */
    if (p->m_slip == 0.0 && !p->quasistationary && !vadmissible(p, L)) return CF_FALLBACK;
    double G = drive(p, Fx, My);
    s.Vb[0] = s.y[0] + 0.5 * h * (G - G) / p->M;
    s.Vb[1] = s.y[0] + 0.5 * h * (G + G) / p->M;
    double v = p->creep_full_slip * py_max(fabs(s.Vb[1]), p->v_scale_floor);
    double sc[3] = {v, v, v / p->a1}, scale[6], u[6];
    for (int i = 0; i < s.n; i++) {
        int a = s.act[i];
        s.un[i] = s.y[a + 1];
        s.F1[i] = s.F2[i] = F[a];
        s.m[i] = algebraic ? 0.0 : m[a];
        scale[i] = scale[s.n + i] = sc[a];
    }
    /* the starts of _newton_from: the algebraic stage from the creepage start, then no
     * slip (_no_slip); the Lobatto stages from the last state, from the creepage start at
     * each stage's speed, then no slip; scipy's hybrid method after the last is left
     * to Python */
    const int n = s.n, N = algebraic ? n : 2 * n;
    double starts[3][6], c0[3], c1[3];
    creep_start(&s, s.Vb[0], c0);
    creep_start(&s, s.Vb[1], c1);
    for (int i = 0; i < n; i++) {
        const int slip_unknown = s.act[i] < 2; /* vx, Vy; not the spin */
        if (algebraic) {
            starts[0][i] = c1[i];
            starts[1][i] = slip_unknown ? 0.0 : c1[i];
        } else {
            starts[0][i] = starts[0][n + i] = s.un[i];
            starts[1][i] = c0[i], starts[1][n + i] = c1[i];
            starts[2][i] = starts[2][n + i] = slip_unknown ? 0.0 : c0[i];
        }
    }
    const int nstarts = algebraic ? 2 : 3;
    const double key = algebraic ? p->algebraic_key : h;
    int kept = w->jac_valid && w->jac_h == key; /* RollingBody._jac for this key */
    int k = 0;
    for (; k < nstarts; k++, kept = 0) { /* after the first, a new matrix */
        for (int i = 0; i < N; i++) u[i] = starts[k][i];
        if (!vnewton(&s, scale, u, w->J, &kept)) break;
    }
    if (k == nstarts) return CF_FALLBACK;
    w->jac_valid = 1, w->jac_h = key;
    double Y[4], T[3];
    vstate_at(&s, algebraic ? u : u + s.n, 1, Y);
    forces_at(p, Y, T, &cache);
    if (algebraic) /* the stage balances the targets: T[act] = F2 */
        for (int i = 0; i < s.n; i++) T[s.act[i]] = s.F2[i];
    return vcommit(p, w, h, Y, T);
}

/* RollingBody._step of the quasistationary method: gross sliding entered where the loads
 * are not admissible, the algebraic stage while rolling (else the Lobatto stages with the
 * masses), then _update_regime */
static int qs_step(const cf_params *p, cf_vstate *w, double h, const double L[4]) {
    if (lifted(p)) return vstep(p, w, h, L, 0); /* free_step, sliding set */
    const int adm = vadmissible(p, L);
    if (!adm) w->sliding = 1;
    if (vstep(p, w, h, L, !w->sliding)) return CF_FALLBACK;
    if (w->sliding) {
        if (!full_slip(p, w->vx, w->Vy, w->Vx) && adm) w->sliding = 0;
    } else if (w->out_sliding) {
        w->sliding = 1;
    }
    return CF_OK;
}

/* RollingBody.advance with Vy and/or Omega_z as unknowns (either method), loads
 * L = (Fx_ex, Fy_ex, My_ex, Mz_ex) held: h (s) in n equal steps. On CF_FALLBACK *y is
 * unchanged. */
static int vstate_finite(const cf_vstate *y) {
    const double v[9] = {y->Vx, y->vx, y->Vy, y->Oz, y->t, y->dv, y->Tx, y->Ty, y->Mz};
    return finite_all(v, 9);
}

/* Vy and Omega_z both held at their ratios, vx the only unknown (a held spin: the native
 * FMU's CF_HELD_SPIN): RollingBody's scalar path, cf_advance, on the vector path's state;
 * Vy and Omega_z follow Vx (_apply_ratios). *y unchanged on CF_FALLBACK. */
static int advance_held(const cf_params *p, cf_vstate *y, double h, const double *L, int n) {
    cf_state s = {.Vx = y->Vx, .vx = y->vx, .t = y->t, .dv = y->dv, .Tx = y->Tx, .Ty = y->Ty,
                  .Mz = y->Mz, .out_sliding = y->out_sliding, .sliding = y->sliding};
    if (cf_advance(p, &s, h, L[0], L[2], n) != CF_OK) return CF_FALLBACK;
    y->Vx = s.Vx, y->vx = s.vx, y->t = s.t, y->dv = s.dv;
    y->Vy = p->ry * s.Vx, y->Oz = p->rz * s.Vx;
    y->Tx = s.Tx, y->Ty = s.Ty, y->Mz = s.Mz;
    y->out_sliding = s.out_sliding, y->sliding = s.sliding;
    y->jac_valid = 0;
    return CF_OK;
}

int cf_advance_vector(const cf_params *p, cf_vstate *y, double h, const double *L, int n) {
    if (p->law == LAW_LAYER && p->strips == NULL && !lifted(p))
        return CF_FALLBACK; /* no spin grid (none needed without contact) */
    if (!(h > 0.0 && h <= DBL_MAX) || n < 1 || !(h / n > 0.0) || !finite_all(L, 4) ||
        !vstate_finite(y))
        return CF_FALLBACK;
    if (!p->dyn_vy && !p->dyn_spin) return advance_held(p, y, h, L, n);
    cf_vstate w = *y;
    if (p->quasistationary && n > 1 && !w.sliding && vadmissible(p, L)) {
        /* RollingBody.advance: rolling under held, admissible loads in one step, unless
         * that step ends in gross sliding */
        if (qs_step(p, &w, h, L) || !vstate_finite(&w)) return CF_FALLBACK;
        if (!w.sliding) {
            w.t = y->t + h;
            if (!isfinite(w.t)) return CF_FALLBACK;
            *y = w;
            return CF_OK;
        }
        w = *y;
    }
    double dt = h / n;
    for (int k = 0; k < n; k++)
        if ((p->quasistationary ? qs_step(p, &w, dt, L) : vstep(p, &w, dt, L, 0)) ||
            !vstate_finite(&w))
            return CF_FALLBACK;
    w.t = y->t + h;
    if (!isfinite(w.t)) return CF_FALLBACK;
    *y = w;
    return CF_OK;
}

/* ---- the native FMU's vector path: the spin grid and the outputs -------------------- */
/* layer._Grid.build for the thin-layer law (a1, a2, p0, mu) on nx x ny cells, into
 * g's arrays (x: nx, y: ny, dist, mid, cap, w: ny x nx, caller's memory) and `inside`
 * (ny x nx bytes): cell centres (2 j + 1 - nx) a1/nx, the strip half-lengths
 * l = a1 (1 - (y/a2)^2)^(1/2) (Eq. 37), the distance marched from the node before (or
 * the leading edge) and its midpoint, mu p (Eq. 33) and the trapezoid weights
 * (layer._strip_weights, times 2 a2/ny), in layer.py's operations. */
void cf_grid_build(cf_strips *g, double *x, double *y, double *dist, double *mid, double *cap,
                   double *w, unsigned char *inside, int nx, int ny, double a1, double a2,
                   double p0, double mu, double k, double tiny) {
    for (int j = 0; j < nx; j++) x[j] = (2.0 * j + 1.0 - nx) * (a1 / nx);
    for (int i = 0; i < ny; i++) y[i] = (2.0 * i + 1.0 - ny) * (a2 / ny);
    const double dx = x[1] - x[0], wy = 2.0 * a2 / ny;
    for (int i = 0; i < ny; i++) {
        const double yr = y[i] / a2, r = 1.0 - yr * yr;
        const double ell = a1 * sqrt(r > 0.0 ? r : 0.0);
        int j0 = -1, j1 = -1;
        for (int j = 0; j < nx; j++) {
            const size_t e = (size_t)i * nx + j;
            inside[e] = fabs(x[j]) < ell;
            const double prev = j > 0 && inside[e - 1] ? x[j - 1] : -ell;
            dist[e] = inside[e] ? x[j] - prev : 0.0;
            mid[e] = inside[e] ? 0.5 * (x[j] + prev) : 0.0;
            const double xr = x[j] / a1, q = 1.0 - xr * xr - yr * yr;
            cap[e] = mu * (p0 * (q > 0.0 ? q : 0.0));
            w[e] = inside[e] ? dx : 0.0;
            if (inside[e]) {
                if (j0 < 0) j0 = j;
                j1 = j;
            }
        }
        if (j0 >= 0) {
            const size_t e0 = (size_t)i * nx + j0, e1 = (size_t)i * nx + j1;
            if (j0 == j1) {
                w[e0] = ell;
            } else {
                w[e0] = 0.5 * dx + 0.5 * (x[j0] + ell);
                w[e1] = 0.5 * dx + 0.5 * (ell - x[j1]);
            }
        }
        for (int j = 0; j < nx; j++) w[(size_t)i * nx + j] *= wy;
    }
    g->ny = ny, g->nx = nx;
    g->x = x, g->y = y, g->dist = dist, g->mid = mid, g->cap = cap, g->w = w;
    g->k = k, g->tiny = tiny;
}

/* RollingBody.__init__'s forces at the initial state of the vector path (the law with
 * spin by the march) and its regime flag */
void cf_initial_vforces(const cf_params *p, cf_vstate *y) {
    march_cache cache = {0, 0.0, 0.0, 0.0, {0.0, 0.0, 0.0}};
    const double Y[4] = {y->Vx, y->vx, y->Vy, y->Oz};
    double T[3];
    forces_at(p, Y, T, &cache);
    y->Tx = T[0], y->Ty = T[1], y->Mz = T[2];
    y->out_sliding = full_slip(p, y->vx, y->Vy, y->Vx);
    y->sliding = 0;
    y->dv = 0.0;
    y->jac_valid = 0;
}

/* LayerContact.adhesion_fraction with spin phi: the share of the area (weights) whose
 * nodes do not slip in the strip march (the same march; its sums in another order than
 * numpy's: equal to rounding); at standstill or for a non-finite input
 * (layer._march_numpy) every node slips where v != 0. tau, slip: scratch (2 ny nx
 * doubles, ny nx bytes); inside: the grid's mask. */
double cf_spin_adhesion(const cf_strips *g, double vx, double vy, double Vx, double phi,
                        double *tau, unsigned char *slip, const unsigned char *inside) {
    const size_t n = (size_t)g->ny * g->nx;
    if (Vx != 0.0 && isfinite(Vx) && isfinite(vx) && isfinite(vy) && isfinite(phi)) {
        double R[3];
        march_one(g, vx, vy, Vx, phi, tau, slip, R);
    } else { /* standstill (layer._march_numpy): slip wherever v != 0 */
        for (int i = 0; i < g->ny; i++)
            for (int j = 0; j < g->nx; j++) {
                const double a = vx - phi * g->y[i], c = vy + phi * g->x[j];
                slip[(size_t)i * g->nx + j] = !(a == 0.0 && c == 0.0);
            }
    }
    double stuck = 0.0, area = 0.0;
    for (size_t e = 0; e < n; e++)
        if (inside[e]) {
            area += g->w[e];
            if (!slip[e]) stuck += g->w[e];
        }
    return area > 0.0 ? stuck / area : 0.0; /* no area (P = 0): nothing adheres */
}

/* RollingBody.outputs() on the vector path into b->out: kinematics, forces and
 * kinematics.contact_quantities; with spin the adhesion of the strip march
 * (cf_spin_adhesion, with its scratch tau, slip and the grid's mask inside). */
void cf_vbody_outputs(const cf_params *p, const cf_vstate *y, cf_body *b, double *tau,
                      unsigned char *slip, const unsigned char *inside) {
    const double Vx = y->Vx, vx = y->vx, Vy = y->Vy, Oz = y->Oz;
    double *o = b->out;
    kinematic_outputs(p, b, Vx, vx, Vy, Oz, y->Tx, y->Ty, y->Mz);
    if (p->law == LAW_TABLE) {
        double t[4];
        table_scalar(p, vx, Vy, Oz, Vx, t);
        o[O_ADHESION] = t[3];
    } else if (Oz == 0.0 || p->strips == NULL || lifted(p)) {
        o[O_ADHESION] = adhesion_fraction(p, vx, Vy, Vx);
    } else {
        o[O_ADHESION] = cf_spin_adhesion((const cf_strips *)p->strips, vx, Vy, Vx, Oz, tau, slip,
                                         inside);
    }
    o[O_REGIME] = full_slip(p, vx, Vy, Vx) ? 1.0 : 0.0;
}

/* ---- fmu/body_model.py: a communication step of the body, checked ------------------- */

/* BodyModel.step with the inputs held and its outputs, with every check of the adapter
 * (cf_body_admit, cf_body_out_check of the outputs served), in place: the scalar path
 * on *y (cf_advance), or with v the vector path on *v->y (cf_advance_vector), the
 * outputs into b->out. CF_OK, or why not (*which: see cf_body_out_check); then the
 * state and b->out hold what the step reached, not to be served: callers step copies.
 * capped: NULL, a step beyond max_substeps internal steps is refused; else it is taken
 * in that many and *capped says so (the caller logs the note). */
int cf_body_check(const cf_params *p, cf_state *y, const cf_vpath *v, cf_body *b,
                  double h, int *capped, unsigned long served, int *which) {
    int n, why = cf_body_admit(p, b, h, &n);
    if (capped != NULL) *capped = why == CF_STEP_CAPPED;
    if (why != CF_OK && !(why == CF_STEP_CAPPED && capped != NULL)) return why;
    const double L[4] = {b->Fx_ex, v ? v->Fy_ex : 0.0, b->My_ex, v ? v->Mz_ex : 0.0};
    /* RollingBody._step: an eta = inf body (m_slip = 0) has no gross sliding; without
     * contact (P = 0, _free_step) an Iy = 0 body takes no moment */
    if (lifted(p) ? p->Iy == 0.0 && L[2] != 0.0
                  : p->m_slip == 0.0 && !p->quasistationary &&
                        !(v != NULL ? vadmissible(p, L) : admissible(p, L[0], L[2])))
        return CF_STEP_NO_SLIDING;
    if (v != NULL) {
        if (cf_advance_vector(p, v->y, h, L, n) != CF_OK) return CF_STEP_NO_ROOT;
        cf_vbody_outputs(p, v->y, b, v->tau, v->slip, v->inside);
    } else {
        if (cf_advance(p, y, h, b->Fx_ex, b->My_ex, n) != CF_OK) return CF_STEP_NO_ROOT;
        cf_body_outputs(p, y, b);
    }
    return cf_body_out_check(b->out, served, which);
}

/* The step of the pythonfmu FMU's fast path (FastBody, fmi.c): cf_body_check of the
 * scalar path on copies, every output served; CF_FALLBACK (*y and *b unchanged) for
 * whatever Python must do (a new load P, the cap on internal steps and its note, a path
 * cf_advance leaves out, a refusal and its message) */
int cf_body_step(const cf_params *p, cf_state *y, cf_body *b, double h) {
    cf_state w = *y;
    cf_body next = *b;
    int which;
    if (cf_body_check(p, &w, NULL, &next, h, NULL, CF_ALL_OUT, &which) != CF_OK)
        return CF_FALLBACK;
    *y = w;
    *b = next;
    return CF_OK;
}

/* ---- the scalar law for the native FMU's contact mode (model.c) -------------------- */
void cf_law_forces(const cf_params *p, double vx, double vy, double Vx, double T[3]) {
    forces(p, vx, vy, Vx, T);
}

void cf_table_forces(const cf_params *p, double vx, double vy, double phi, double Vx,
                     double out[4]) {
    table_scalar(p, vx, vy, phi, Vx, out);
}

double cf_adhesion_fraction(const cf_params *p, double vx, double vy, double Vx) {
    return adhesion_fraction(p, vx, vy, Vx);
}

int cf_full_slip(const cf_params *p, double vx, double vy, double Vx) {
    return full_slip(p, vx, vy, Vx);
}

double cf_target_x(const cf_params *p, double Fx, double My) { return target_x(p, Fx, My); }

double cf_force_fraction(const cf_params *p, double beta) { return force_fraction(p, beta); }

double cf_force_fraction_slope(const cf_params *p, double beta) {
    return force_fraction_slope(p, beta);
}
