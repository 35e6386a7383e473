/* The thin-layer transient traction field in C (field.h): transient.py's
 * LayerField.stage, LayerField._weights, _capped_linear, StageField.resultant,
 * LayerField.summary and TransientRollingBody's scalar step, expression by expression
 * and in the same order, so that they agree with the Python reference to rounding. Two sources of difference remain, both of a few ulp:
 * numpy's power z**3 (its own SIMD routine where the CPU has one; z z z here, a third of
 * the cost of pow and as close to it) and hypot.
 * The sums over the grid are numpy's pairwise summation (np.add.reduce over a
 * contiguous array), reproduced by pairwise_sum. No globals, no allocation: the caller
 * passes every array. Every input is checked (CF_FIELD_BAD_INPUT, CF_FIELD_RANGE) and
 * every result too (CF_FIELD_NONFINITE): a huge finite input that overflows is not
 * served; the Python path then takes the call. */
#include "field.h"

#include <stddef.h>

/* numpy's pairwise summation of n contiguous doubles (DOUBLE_pairwise_sum in
 * numpy/_core/src/umath/loops_utils.h.src): blocks of at most 128 summed in 8 partial
 * sums, larger arrays split in halves of a multiple of 8. With the reduction's initial
 * 0.0 (exact), np.sum of a contiguous float64 array is this sum. */
static double pairwise_sum(const double *a, size_t n) {
    if (n < 8) {
        double res = 0.0;
        for (size_t i = 0; i < n; i++) res += a[i];
        return res;
    }
    if (n <= 128) {
        double r[8];
        size_t i;
        for (int j = 0; j < 8; j++) r[j] = a[j];
        for (i = 8; i < n - (n % 8); i += 8)
            for (int j = 0; j < 8; j++) r[j] += a[i + (size_t)j];
        double res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; i++) res += a[i];
        return res;
    }
    size_t n2 = n / 2;
    n2 -= n2 % 8;
    return pairwise_sum(a, n2) + pairwise_sum(a + n2, n - n2);
}

/* np.maximum and np.minimum (NaN propagates from either side) */
static double np_max(double a, double b) { return (a >= b || isnan(a)) ? a : b; }
static double np_min(double a, double b) { return (a <= b || isnan(a)) ? a : b; }

/* z**3 of the antiderivative of mu p: within an ulp of numpy's and of pow, faster */
static double cube(double z) { return z * z * z; }

/* int_lo^hi min(L, mu p) dx, L(x) = ma + bs (x - xa) >= 0, mu p = c0 (l2 - x^2)
 * (transient._capped_linear) */
static double cap_int(double c0, double l2, double z) { return c0 * (l2 * z - cube(z) / 3.0); }

static double lin_int(double ma, double bs, double xa, double z) {
    double d = z - xa;
    return ma * z + 0.5 * bs * (d * d);
}

static double capped_linear(double c0, double l2, double xa, double ma, double bs, double lo,
                            double hi) {
    double disc = bs * bs + 4.0 * c0 * (c0 * l2 - ma + bs * xa);
    double sq = sqrt(np_max(disc, 0.0));
    double r1 = (-bs - sq) / (2.0 * c0);
    double r2 = (-bs + sq) / (2.0 * c0);
    double o_lo = np_max(lo, r1);
    double o_hi = np_max(np_min(hi, r2), o_lo);
    if (!(disc > 0.0)) o_hi = o_lo;
    double below = (cap_int(c0, l2, o_hi) - cap_int(c0, l2, o_lo)) -
                   (lin_int(ma, bs, xa, o_hi) - lin_int(ma, bs, xa, o_lo));
    return cap_int(c0, l2, hi) - cap_int(c0, l2, lo) - below;
}

static int all_finite(const double *a, size_t n) {
    for (size_t i = 0; i < n; i++)
        if (!isfinite(a[i])) return 0;
    return 1;
}

static int field_ok(const cf_field *f) {
    if (f == NULL || f->y == NULL || f->ell == NULL || f->p_strip == NULL || f->dy_w == NULL)
        return 0;
    if (f->nx < 2 || f->ny < 1) return 0;
    const double pos[] = {f->dx, f->X, f->a1, f->p0, f->mu, f->k, f->c0};
    for (size_t i = 0; i < sizeof pos / sizeof pos[0]; i++)
        if (!(isfinite(pos[i]) && pos[i] > 0.0)) return 0;
    size_t ny = (size_t)f->ny;
    return all_finite(f->y, ny) && all_finite(f->ell, ny) && all_finite(f->p_strip, ny) &&
           all_finite(f->dy_w, ny);
}

/* The weights of one strip i (LayerField._weights, its passes in its order). m: |tau|
 * of the row, or NULL for area weights; cap_at, inv: scratch of nx doubles each. */
static void row_weights(const cf_field *f, int i, const double *x, const unsigned char *in,
                        const double *m, const unsigned char *sl_raw, double sign, double *w,
                        double *cap_at, double *inv) {
    const int nx = f->nx;
    const double dx = f->dx, ell = f->ell[i];
    int j_lo = -1, j_hi = -1;
    for (int j = 0; j < nx; j++) {
        w[j] = 0.0;
        if (in[j]) {
            if (j_lo < 0) j_lo = j;
            j_hi = j;
        }
    }
    if (m == NULL) { /* area weights: each interval shared equally */
        for (int j = 0; j + 1 < nx; j++)
            if (in[j] && in[j + 1]) w[j] += 0.5 * dx;
        for (int j = 1; j < nx; j++)
            if (in[j - 1] && in[j]) w[j] += 0.5 * dx;
        if (j_lo >= 0) {
            w[j_lo] += x[j_lo] + ell;
            w[j_hi] += ell - x[j_hi];
        }
        for (int j = 0; j < nx; j++) w[j] *= f->dy_w[i];
        return;
    }
    const double c0 = f->c0, l2 = ell * ell;
#define SL(j) (sl_raw != NULL && sl_raw[j] && in[j])
#define ADH(j) (in[j] && !SL(j))
#define PAIR(j) (in[j] && in[(j) + 1])
#define INV(j) inv[j]
    for (int j = 0; j < nx; j++) inv[j] = m[j] > 0.0 ? 1.0 / m[j] : 0.0;
    /* A-A: trapezoid */
    for (int j = 0; j + 1 < nx; j++)
        if (PAIR(j) && !SL(j) && !SL(j + 1)) w[j] += 0.5 * dx;
    for (int j = 1; j < nx; j++)
        if (PAIR(j - 1) && !SL(j - 1) && !SL(j)) w[j] += 0.5 * dx;
    /* S-S: the cap, shared equally (added everywhere as numpy does: 0 * inv_m) */
    for (int j = 0; j < nx; j++) cap_at[j] = cap_int(c0, l2, x[j]); /* antiderivative of mu p */
    for (int j = 0; j + 1 < nx; j++) {
        const double hc = PAIR(j) && SL(j) && SL(j + 1) ? 0.5 * (cap_at[j + 1] - cap_at[j]) : 0.0;
        w[j] += hc * INV(j);
    }
    for (int j = 0; j + 1 < nx; j++) {
        const double hc = PAIR(j) && SL(j) && SL(j + 1) ? 0.5 * (cap_at[j + 1] - cap_at[j]) : 0.0;
        w[j + 1] += hc * INV(j + 1);
    }
    /* transitions: adhering node a, slipping neighbour on the side sd */
    for (int sd = 1; sd >= -1; sd -= 2) {
        for (int j0 = 0; j0 + 1 < nx; j0++) {
            int hit = sd > 0 ? (PAIR(j0) && !SL(j0) && SL(j0 + 1))
                             : (PAIR(j0) && SL(j0) && !SL(j0 + 1));
            if (!hit) continue;
            int a = sd > 0 ? j0 : j0 + 1, back = a - sd;
            int ok = back >= 0 && back < nx && ADH(back);
            double slope = ok ? (m[a] - m[back]) / dx : (m[a + sd] - m[a]) / dx;
            double lo = np_min(x[a], x[a + sd]);
            double seg = capped_linear(c0, l2, x[a], m[a], sd * slope, lo, lo + dx);
            if (m[a] > 0.0)
                w[a] += seg * INV(a);
            else
                w[a + sd] += seg * INV(a + sd);
        }
    }
    /* end segments to the strip ends: j_lo towards -l, then j_hi towards +l */
    if (j_lo >= 0) {
        for (int side = -1; side <= 1; side += 2) {
            int j = side < 0 ? j_lo : j_hi;
            int is_lead = side < 0 ? sign < 0.0 : sign > 0.0;
            double e = ell - side * x[j];
            double lo = side > 0 ? x[j] : x[j] - e;
            double mj = m[j];
            double ci = cap_int(c0, l2, lo + e) - cap_int(c0, l2, lo);
            int inner = j - side;
            int ok = inner >= 0 && inner < nx && ADH(inner);
            double slope = ok ? (mj - m[inner]) / dx : 0.0;
            slope = np_max(slope, e > 0.0 ? -mj / e : 0.0); /* L >= 0 on the segment */
            double seg;
            if (SL(j))
                seg = ci;
            else if (is_lead)
                seg = 0.5 * e * mj;
            else
                seg = capped_linear(c0, l2, x[j], mj, side * slope, lo, lo + e);
            w[j] += mj > 0.0 ? seg * INV(j) : e;
        }
    }
#undef SL
#undef ADH
#undef PAIR
#undef INV
    for (int j = 0; j < nx; j++) w[j] *= f->dy_w[i];
}

static int weights(const cf_field *f, const double *x, const unsigned char *inside,
                   const double *tau_x, const double *tau_y, const unsigned char *slip,
                   double sign, double *w, double *m) {
    const size_t nx = (size_t)f->nx;
    for (int i = 0; i < f->ny; i++) {
        const size_t r = (size_t)i * nx;
        if (tau_x != NULL)
            for (size_t j = 0; j < nx; j++) { /* hypot(+-0, +-0) = +0: no call for it */
                const double a = tau_x[r + j], b = tau_y[r + j];
                m[j] = a == 0.0 && b == 0.0 ? 0.0 : hypot(a, b);
            }
        row_weights(f, i, x, inside + r, tau_x != NULL ? m : NULL,
                    slip != NULL ? slip + r : NULL, sign, w + r, m + nx, m + 2 * nx);
    }
    return all_finite(w, nx * (size_t)f->ny) ? CF_FIELD_OK : CF_FIELD_NONFINITE;
}

int cf_field_weights(const cf_field *f, const double *x, const unsigned char *inside,
                     const double *tau_x, const double *tau_y, const unsigned char *slip,
                     double sign, double *w, double *work) {
    if (!field_ok(f) || x == NULL || inside == NULL || w == NULL || work == NULL ||
        !isfinite(sign) || (tau_x == NULL) != (tau_y == NULL))
        return CF_FIELD_BAD_INPUT;
    const size_t nx = (size_t)f->nx, n = nx * (size_t)f->ny;
    if (!all_finite(x, nx)) return CF_FIELD_BAD_INPUT;
    if (tau_x != NULL && !(all_finite(tau_x, n) && all_finite(tau_y, n)))
        return CF_FIELD_BAD_INPUT;
    return weights(f, x, inside, tau_x, tau_y, slip, sign, w, work);
}

int cf_field_resultant(const cf_field *f, const double *x, const double *w,
                       const double *tau_x, const double *tau_y, double *work, double T[3]) {
    if (!field_ok(f) || x == NULL || w == NULL || tau_x == NULL || tau_y == NULL ||
        work == NULL || T == NULL)
        return CF_FIELD_BAD_INPUT;
    const size_t nx = (size_t)f->nx, ny = (size_t)f->ny, n = nx * ny;
    for (size_t k = 0; k < n; k++) work[k] = w[k] * tau_x[k];
    T[0] = pairwise_sum(work, n);
    for (size_t k = 0; k < n; k++) work[k] = w[k] * tau_y[k];
    T[1] = pairwise_sum(work, n);
    for (size_t i = 0; i < ny; i++)
        for (size_t j = 0, k = i * nx; j < nx; j++, k++) work[k] = (w[k] * x[j]) * tau_y[k];
    double a = pairwise_sum(work, n);
    for (size_t i = 0; i < ny; i++)
        for (size_t j = 0, k = i * nx; j < nx; j++, k++) work[k] = (w[k] * f->y[i]) * tau_x[k];
    T[2] = a - pairwise_sum(work, n);
    return all_finite(T, 3) ? CF_FIELD_OK : CF_FIELD_NONFINITE;
}

int cf_field_stage(const cf_field *f, const cf_field_stage_in *in, cf_field_stage_out *out) {
    if (!field_ok(f) || !(isfinite(f->min_speed_fraction) && f->min_speed_fraction >= 0.0))
        return CF_FIELD_BAD_INPUT;
    if (in == NULL || out == NULL || in->inside == NULL || in->hat_x == NULL ||
        in->hat_y == NULL || out->x == NULL || out->tau_x == NULL || out->tau_y == NULL ||
        out->w == NULL || out->slip == NULL || out->inside == NULL || out->work == NULL)
        return CF_FIELD_BAD_INPUT;
    const double scalars[] = {in->theta, in->ds,  in->elapsed, in->h_own,
                              in->vx,    in->vy,  in->phi,     in->Vx};
    if (!all_finite(scalars, sizeof scalars / sizeof scalars[0])) return CF_FIELD_BAD_INPUT;
    const int nx = f->nx, ny = f->ny;
    const size_t n = (size_t)nx * (size_t)ny;
    if (!(all_finite(in->hat_x, n) && all_finite(in->hat_y, n))) return CF_FIELD_BAD_INPUT;
    const double k = f->k, ds = in->ds, phi = in->phi;
    /* the lattice after rolling ds: whole columns re-indexed, theta the remainder */
    const double u = in->theta - ds / f->dx;
    const double fl = floor(u);
    if (!(fabs(fl) <= CF_FIELD_SHIFT_MAX)) return CF_FIELD_RANGE; /* inf and NaN too */
    const long long shift = (long long)fl;
    const double theta = u - fl;
    out->theta = theta;
    out->shift = shift;
    const double sgn = ds > 0.0 ? 1.0 : (ds < 0.0 ? -1.0 : 0.0);
    double *x = out->x;
    for (int j = 0; j < nx; j++) x[j] = -f->X + ((double)j + theta) * f->dx;
    /* scratch: the tangent's entries, the nodes' g, products for the sums, then the
     * weights' two rows (prod + n) */
    double *Dxx = out->work, *Dxy = Dxx + n, *Dyy = Dxy + n, *g = Dyy + n, *prod = g + n;
    /* inside the ellipse now, and whether any material entered during the step */
    int any_entered = 0;
    for (int i = 0; i < ny; i++)
        for (int j = 0; j < nx; j++) {
            const size_t r = (size_t)i * (size_t)nx + (size_t)j;
            const long long src = (long long)j - shift;
            const int was = src >= 0 && src < nx && in->inside[(size_t)i * (size_t)nx + (size_t)src];
            out->inside[r] = fabs(x[j]) < f->ell[i];
            any_entered |= out->inside[r] && !was;
        }
    const int timed = ds != 0.0 && any_entered;
    double *p_col = prod; /* p0 (x/a1)^2 by column (prod is free until the weights) */
    for (int j = 0; j < nx; j++) {
        const double xa = x[j] / f->a1;
        p_col[j] = f->p0 * (xa * xa);
    }
    const double own_k = in->h_own / k;
    const int by_speed = fabs(in->Vx) * in->elapsed > f->min_speed_fraction * fabs(ds);
    for (int i = 0; i < ny; i++) {
        const double rvx = in->vx - phi * f->y[i];
        for (int j = 0; j < nx; j++) {
            const size_t r = (size_t)i * (size_t)nx + (size_t)j;
            const long long src = (long long)j - shift;
            const int valid = src >= 0 && src < nx;
            const size_t rs = valid ? (size_t)i * (size_t)nx + (size_t)src : 0;
            const int inside = out->inside[r];
            const int entered = inside && !(valid && in->inside[rs]);
            const double p = f->p_strip[i] - p_col[j];
            const double cap = f->mu * (inside ? np_max(p, 0.0) : 0.0);
            const double d_in = f->ell[i] - sgn * x[j]; /* distance from the leading edge */
            double rvy;
            if (in->midpath && phi != 0.0) {
                const double back = 0.5 * sgn * (entered ? d_in : fabs(ds));
                rvy = in->vy + phi * (x[j] + back);
            } else {
                rvy = in->vy + phi * x[j];
            }
            double hx = valid ? in->hat_x[rs] : 0.0, hy = valid ? in->hat_y[rs] : 0.0;
            double t_eff = in->h_own;
            if (timed && entered) {
                if (by_speed)
                    t_eff = np_max(d_in, 0.0) / fabs(in->Vx);
                else
                    t_eff = np_min(np_max(in->elapsed * d_in / fabs(ds), 0.0), in->elapsed);
                hx = 0.0;
                hy = 0.0;
            }
            const double tk = t_eff == in->h_own ? own_k : t_eff / k;
            double tx = hx + rvx * tk;
            double ty = hy + rvy * tk;
            g[r] = t_eff; /* until the weights are known */
            if (!inside) { /* cap 0: any trial slips to 0; no weight, so no tangent */
                const int slip = tx != 0.0 || ty != 0.0; /* hypot > 0 */
                out->tau_x[r] = slip ? tx * 0.0 : tx;
                out->tau_y[r] = slip ? ty * 0.0 : ty;
                out->slip[r] = (unsigned char)slip;
                Dxx[r] = Dxy[r] = Dyy[r] = 0.0;
                continue;
            }
            const double mag = hypot(tx, ty);
            const int slip = mag > cap;
            /* the radial return onto |tau| <= mu p and its tangent (cap/|t|)(I - n n^T) */
            const double fct = slip ? cap / mag : 1.0;
            const double nxn = slip ? tx / mag : 0.0, nyn = slip ? ty / mag : 0.0;
            Dxx[r] = fct * (1.0 - nxn * nxn);
            Dxy[r] = -fct * nxn * nyn;
            Dyy[r] = fct * (1.0 - nyn * nyn);
            out->tau_x[r] = tx * fct;
            out->tau_y[r] = ty * fct;
            out->slip[r] = (unsigned char)slip;
        }
    }
    if (!(all_finite(out->tau_x, n) && all_finite(out->tau_y, n))) return CF_FIELD_NONFINITE;
    int rc = weights(f, x, out->inside, out->tau_x, out->tau_y, out->slip, sgn, out->w, prod + n);
    if (rc != CF_FIELD_OK) return rc;
    for (size_t r = 0; r < n; r++) {
        out->slip[r] = out->slip[r] && out->inside[r];
        g[r] = out->w[r] * g[r] / k; /* d(node force)/d(trial) per unit slip velocity */
    }
    for (size_t r = 0; r < n; r++) prod[r] = g[r] * Dxx[r];
    out->dTx_dvx = pairwise_sum(prod, n);
    for (int c = 0; c < 9; c++) out->J[c] = 0.0;
    if (in->jacobian) {
        /* column c: d/dvx -> (Dxx, Dxy); d/dvy -> (Dxy, Dyy); d/dphi -> D (-y, x) */
        for (int c = 0; c < 3; c++)
            for (int row = 0; row < 3; row++) {
                for (size_t r = 0; r < n; r++) {
                    const size_t i = r / (size_t)nx;
                    const double X = x[r - i * (size_t)nx], Y = f->y[i];
                    double cx, cy;
                    if (c == 0) {
                        cx = Dxx[r];
                        cy = Dxy[r];
                    } else if (c == 1) {
                        cx = Dxy[r];
                        cy = Dyy[r];
                    } else {
                        cx = -Y * Dxx[r] + X * Dxy[r];
                        cy = -Y * Dxy[r] + X * Dyy[r];
                    }
                    prod[r] = g[r] * (row == 0 ? cx : (row == 1 ? cy : X * cy - Y * cx));
                }
                out->J[3 * row + c] = pairwise_sum(prod, n);
            }
    }
    rc = cf_field_resultant(f, x, out->w, out->tau_x, out->tau_y, prod, out->T);
    if (rc != CF_FIELD_OK) return rc;
    if (!(isfinite(out->dTx_dvx) && all_finite(out->J, 9))) return CF_FIELD_NONFINITE;
    return CF_FIELD_OK;
}

/* ---- TransientRollingBody.advance: vx, and Vy and/or Omega_z where they are unknowns ---- */

/* One SDIRK2 stage's problem (TransientRollingBody._stage for the unknown vx): the
 * stage's field inputs and the body's numbers around them. */
typedef struct {
    const cf_field *f;
    const cf_field_body *b;
    double y_hat[4];
    double Vx_base, u_hat, target, m_h, ds0, elapsed, hg;
    cf_field_stage_in in;
    cf_field_stage_out *out;
    double yy[4]; /* the state at the last evaluation */
    /* Vy and/or Omega_z as unknowns too: u = (vx[, Vy][, Omega_z]), n of them, the
     * state's index of each, the resultant's (act), their masses and targets, and the
     * field's evaluations of this advance (evals, against b->eval_limit) */
    int n, idx[3], act[3];
    double m[3], targets[3], uh[3];
    int *evals;
} stage_problem;

/* the stage's field at the state sp->yy = (Vx, vx, Vy, Omega_z): the travel over the
 * stage ds0 + h gamma Vx and the creepages' kinematics */
static int stage_at(stage_problem *sp) {
    const double *yy = sp->yy;
    sp->in.ds = sp->ds0 + sp->hg * yy[0];
    sp->in.vx = yy[1];
    sp->in.vy = yy[2];
    sp->in.phi = yy[3];
    sp->in.Vx = yy[0];
    return cf_field_stage(sp->f, &sp->in, sp->out);
}

/* state(u) and evaluate(u): the stage's field at vx = u; r, d: the residual and its
 * derivative (m_h + dTx/dvx) */
static int evaluate(stage_problem *sp, double u, double *r, double *d) {
    const cf_field_body *b = sp->b;
    double *yy = sp->yy;
    yy[0] = sp->Vx_base + (b->m_slip / b->M) * (u - sp->u_hat);
    yy[1] = u;
    yy[2] = b->ry * yy[0];
    yy[3] = b->rz * yy[0];
    const int rc = stage_at(sp);
    if (rc != CF_FIELD_OK) return rc;
    *r = sp->m_h * (u - sp->u_hat) + sp->out->T[0] - sp->target;
    *d = sp->m_h + sp->out->dTx_dvx;
    return isfinite(*r) && isfinite(*d) ? CF_FIELD_OK : CF_FIELD_NONFINITE;
}

/* TransientRollingBody._solve_scalar: Newton's method with the field's tangent inside
 * the bracket its iterates build; the stage's field is left at the root's evaluation */
static int solve_scalar(stage_problem *sp, double scale) {
    double lo = -INFINITY, hi = INFINITY, u = sp->u_hat, r, d;
    int rc = evaluate(sp, u, &r, &d);
    if (rc != CF_FIELD_OK) return rc;
    for (int it = 0; it < sp->b->max_iterations; it++) {
        if (r == 0.0) return CF_FIELD_OK;
        if (r > 0.0)
            hi = u;
        else
            lo = u;
        const double step = d > 0.0 ? -r / d : copysign(scale, -r);
        const double tol = sp->b->solve_rtol * (scale + fabs(u));
        if (fabs(step) <= tol) return CF_FIELD_OK;
        double un = u + step;
        const int bracketed = isfinite(lo) && isfinite(hi);
        if (!(lo < un && un < hi)) un = bracketed ? 0.5 * (lo + hi) : u + 4.0 * step;
        if (bracketed && hi - lo <= tol) return CF_FIELD_OK;
        u = un;
        rc = evaluate(sp, u, &r, &d);
        if (rc != CF_FIELD_OK) return rc;
    }
    return CF_FIELD_NO_ROOT;
}

/* _stage's vector(u), Vy and/or Omega_z unknowns too: the state (state(u): y_hat with
 * the unknowns, Vx from vx, the held ratios), the field's stage with its Jacobian, the
 * residuals r = m (u - u_hat)/h gamma + T[act] - target and their Jacobian J = diag(m/h
 * gamma) + dT[act]/d(vx, vy, phi)[cols] (n x n, row major), each an evaluation spent
 * (EvalBudget.spend: beyond b->eval_limit, CF_FIELD_BUDGET) */
static int evaluate_vector(stage_problem *sp, const double *u, double *r, double *J) {
    const cf_field_body *b = sp->b;
    if (b->eval_limit > 0 && ++*sp->evals > b->eval_limit) return CF_FIELD_BUDGET;
    double *yy = sp->yy;
    for (int i = 0; i < 4; i++) yy[i] = sp->y_hat[i];
    for (int i = 0; i < sp->n; i++) yy[sp->idx[i]] = u[i];
    yy[0] = sp->Vx_base + (b->m_slip / b->M) * (u[0] - sp->uh[0]);
    if (!b->dyn_vy) yy[2] = b->ry * yy[0]; /* BodyState._apply_ratios */
    if (!b->dyn_spin) yy[3] = b->rz * yy[0];
    const int rc = stage_at(sp);
    if (rc != CF_FIELD_OK) return rc;
    for (int i = 0; i < sp->n; i++) {
        r[i] = sp->m[i] * (u[i] - sp->uh[i]) / sp->hg + sp->out->T[sp->act[i]] - sp->targets[i];
        for (int j = 0; j < sp->n; j++)
            J[i * sp->n + j] = (i == j ? sp->m[i] / sp->hg : 0.0) +
                               sp->out->J[3 * sp->act[i] + sp->act[j]];
    }
    return all_finite(r, (size_t)sp->n) && all_finite(J, (size_t)(sp->n * sp->n))
               ? CF_FIELD_OK : CF_FIELD_NONFINITE;
}

/* J x = -r for n <= 3 by Gaussian elimination with partial pivoting (numpy's LAPACK runs
 * its operations in another order: the iterates agree to rounding); 0, or -1 singular */
static int solve_negated(int n, const double *J0, const double *r, double *x) {
    double A[9], b[3];
    for (int i = 0; i < n * n; i++) A[i] = J0[i];
    for (int i = 0; i < n; i++) b[i] = -r[i];
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[p * n + k])) p = i;
        if (A[p * n + k] == 0.0 || !isfinite(A[p * n + k])) return -1;
        if (p != k) {
            for (int j = 0; j < n; j++) {
                const double t = A[k * n + j];
                A[k * n + j] = A[p * n + j];
                A[p * n + j] = t;
            }
            const double t = b[k];
            b[k] = b[p];
            b[p] = t;
        }
        for (int i = k + 1; i < n; i++) {
            const double l = A[i * n + k] / A[k * n + k];
            for (int j = k; j < n; j++) A[i * n + j] -= l * A[k * n + j];
            b[i] -= l * b[k];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double t = b[i];
        for (int j = i + 1; j < n; j++) t -= A[i * n + j] * x[j];
        x[i] = t / A[i * n + i];
    }
    return all_finite(x, (size_t)n) ? 0 : -1;
}

static double norm_of(const double *r, int n) {
    double s = 0.0;
    for (int i = 0; i < n; i++) s += r[i] * r[i];
    return sqrt(s);
}

/* TransientRollingBody._solve_vector: Newton's method with the field's Jacobian from
 * u_hat, a backtracking line search (halving down to 1e-6) on |r|; converged when every
 * correction is below solve_rtol (scale_i + |u_i|), the stage's field left at that
 * evaluation. Where it stalls (a singular matrix, the line search at its floor, the
 * iterations spent) Python calls scipy's hybrid method: CF_FIELD_NO_ROOT here. */
static int solve_vector(stage_problem *sp, const double *scale) {
    const int n = sp->n;
    double u[3], r[3], J[9], step[3], un[3], rn[3], Jn[9];
    for (int i = 0; i < n; i++) u[i] = sp->uh[i];
    int rc = evaluate_vector(sp, u, r, J);
    if (rc != CF_FIELD_OK) return rc;
    for (int it = 0; it < sp->b->max_iterations; it++) {
        if (solve_negated(n, J, r, step) != 0) return CF_FIELD_NO_ROOT;
        int small = 1;
        for (int i = 0; i < n; i++)
            small = small && fabs(step[i]) <= sp->b->solve_rtol * (scale[i] + fabs(u[i]));
        if (small) return CF_FIELD_OK;
        const double norm0 = norm_of(r, n);
        double lam = 1.0;
        for (;;) {
            for (int i = 0; i < n; i++) un[i] = u[i] + lam * step[i];
            rc = evaluate_vector(sp, un, rn, Jn);
            if (rc != CF_FIELD_OK) return rc;
            if (norm_of(rn, n) < norm0 || lam < 1e-6) break;
            lam *= 0.5;
        }
        if (lam < 1e-6) return CF_FIELD_NO_ROOT;
        for (int i = 0; i < n; i++) u[i] = un[i], r[i] = rn[i];
        for (int i = 0; i < n * n; i++) J[i] = Jn[i];
    }
    return CF_FIELD_NO_ROOT;
}

/* TransientRollingBody._stage: the stage problem from y_hat (L = Fx_ex, Fy_ex, My_ex,
 * Mz_ex), solved for vx alone (_solve_scalar) or with Vy and/or Omega_z (_solve_vector) */
static int stage_solve(stage_problem *sp, const double y_hat[4], const double *L, double hg,
                       double ds0, double elapsed) {
    const cf_field_body *b = sp->b;
    for (int i = 0; i < 4; i++) sp->y_hat[i] = y_hat[i];
    sp->target = b->A2 * L[0] - b->A1 * L[2] / b->Rx;
    sp->Vx_base = y_hat[0] + hg * b->A1 * (L[0] + L[2] / b->Rx) / b->M;
    sp->u_hat = y_hat[1];
    sp->m_h = b->m_slip / hg;
    sp->hg = hg;
    sp->ds0 = ds0;
    sp->in.elapsed = elapsed;
    sp->in.h_own = hg;
    const double vscale = b->creep_full_slip * np_max(fabs(sp->Vx_base), b->v_scale_floor);
    if (!b->dyn_vy && !b->dyn_spin) return solve_scalar(sp, vscale);
    /* _targets, _masses, the unknowns' indices; the scales (vscale, vscale, vscale/a1)
     * taken in order for the n unknowns, as Python slices them */
    int n = 0;
    const double all_scale[3] = {vscale, vscale, vscale / b->a1};
    double scale[3];
    sp->idx[n] = 1, sp->act[n] = 0, sp->m[n] = b->m_slip, sp->targets[n] = sp->target, n++;
    if (b->dyn_vy) sp->idx[n] = 2, sp->act[n] = 1, sp->m[n] = b->M, sp->targets[n] = L[1], n++;
    if (b->dyn_spin) sp->idx[n] = 3, sp->act[n] = 2, sp->m[n] = b->Iz, sp->targets[n] = L[3], n++;
    sp->n = n;
    for (int i = 0; i < n; i++) sp->uh[i] = y_hat[sp->idx[i]], scale[i] = all_scale[i];
    sp->in.jacobian = 1;
    return solve_vector(sp, scale);
}

/* TransientRollingBody._step: one SDIRK2 step of h (Alexander's: c = (gamma, 1)) */
static int sdirk_step(const cf_field *f, const cf_field_body *b, cf_field_body_state *s,
                      double h, const double *L, int *evals) {
    const int nx = f->nx, ny = f->ny;
    const size_t n = (size_t)nx * (size_t)ny;
    double *hat_x = s->work, *hat_y = hat_x + n, *x = hat_y + n, *tx = x + nx, *ty = tx + n;
    double *w = ty + n, *work = w + n;
    unsigned char *inside = s->bytes, *slip = inside + n, *ins = slip + n;
    cf_field_stage_out out = {0.0, 0, x, tx, ty, w, slip, ins, work, {0.0, 0.0, 0.0}, 0.0, {0.0}};
    const double hg = h * b->gamma;
    /* begin: the base of the step */
    for (int i = 0; i < ny; i++)
        for (int j = 0; j < nx; j++)
            inside[(size_t)i * (size_t)nx + (size_t)j] =
                fabs(-f->X + ((double)j + s->theta) * f->dx) < f->ell[i];
    stage_problem sp;
    sp.f = f;
    sp.b = b;
    sp.out = &out;
    sp.evals = evals;
    sp.in.theta = s->theta;
    sp.in.inside = inside;
    sp.in.hat_x = s->tau_x;
    sp.in.hat_y = s->tau_y;
    sp.in.midpath = 0;
    sp.in.jacobian = 0;
    const double y_n[4] = {s->y[0], s->y[1], s->y[2], s->y[3]};
    int rc = stage_solve(&sp, y_n, L, hg, 0.0, hg);
    if (rc != CF_FIELD_OK) return rc;
    double y1[4], y_hat[4];
    for (int i = 0; i < 4; i++) {
        y1[i] = sp.yy[i];
        const double k1 = (y1[i] - y_n[i]) / hg;
        y_hat[i] = y_n[i] + h * b->a21 * k1;
    }
    const double T1[3] = {out.T[0], out.T[1], out.T[2]};
    /* to_base: stage 1's field in base indexing; tau_hat = tau_n + c (b1 - tau_n) */
    const double c = b->a21 / b->gamma;
    for (int i = 0; i < ny; i++)
        for (int j = 0; j < nx; j++) {
            const size_t r = (size_t)i * (size_t)nx + (size_t)j;
            double b1x = s->tau_x[r], b1y = s->tau_y[r];
            if (inside[r]) {
                const long long idx = (long long)j + out.shift;
                const int valid = idx >= 0 && idx < nx;
                b1x = valid ? tx[(size_t)i * (size_t)nx + (size_t)idx] : 0.0;
                b1y = valid ? ty[(size_t)i * (size_t)nx + (size_t)idx] : 0.0;
            }
            hat_x[r] = s->tau_x[r] + c * (b1x - s->tau_x[r]);
            hat_y[r] = s->tau_y[r] + c * (b1y - s->tau_y[r]);
        }
    const double ds1 = h * b->a21 * y1[0];
    sp.in.hat_x = hat_x;
    sp.in.hat_y = hat_y;
    rc = stage_solve(&sp, y_hat, L, hg, ds1, h);
    if (rc != CF_FIELD_OK) return rc;
    /* stiffly accurate: the last stage is the step's result; commit its field */
    for (int i = 0; i < 4; i++) s->y[i] = sp.yy[i];
    s->theta = out.theta;
    s->direction = sp.in.ds > 0.0 ? 1.0 : (sp.in.ds < 0.0 ? -1.0 : 0.0);
    int any_inside = 0, any_adhesion = 0;
    for (size_t r = 0; r < n; r++) {
        s->tau_x[r] = tx[r];
        s->tau_y[r] = ty[r];
        s->slip[r] = slip[r];
        any_inside |= ins[r];
        any_adhesion |= ins[r] && !slip[r];
    }
    for (int i = 0; i < 3; i++) {
        s->impulse[i] += h * (b->a21 * T1[i] + b->gamma * out.T[i]);
        s->T[i] = out.T[i];
    }
    s->sliding = any_inside && !any_adhesion;
    return CF_FIELD_OK;
}

int cf_field_advance(const cf_field *f, const cf_field_body *b, cf_field_body_state *s,
                     double h, const double loads[4], int substeps) {
    if (!field_ok(f) || b == NULL || s == NULL || loads == NULL || s->tau_x == NULL ||
        s->tau_y == NULL || s->slip == NULL || s->work == NULL || s->bytes == NULL)
        return CF_FIELD_BAD_INPUT;
    const double numbers[] = {b->M,    b->Rx,        b->A1,    b->A2,         b->m_slip,
                              b->ry,   b->rz,        b->gamma, b->a21,        b->creep_full_slip,
                              b->solve_rtol, b->v_scale_floor, h, s->t, s->theta,
                              loads[0], loads[1], loads[2], loads[3]};
    if (!all_finite(numbers, sizeof numbers / sizeof numbers[0]) || !all_finite(s->y, 4) ||
        !all_finite(s->impulse, 3))
        return CF_FIELD_BAD_INPUT;
    if (!(b->M > 0.0 && b->Rx > 0.0 && b->gamma > 0.0 && h > 0.0 && substeps >= 1 &&
          b->max_iterations >= 1))
        return CF_FIELD_BAD_INPUT;
    if ((b->dyn_vy || b->dyn_spin) && !(b->a1 > 0.0 && isfinite(b->a1) && (!b->dyn_spin ||
                                         (b->Iz > 0.0 && isfinite(b->Iz)))))
        return CF_FIELD_BAD_INPUT;
    const double dt = h / substeps, t0 = s->t;
    int evals = 0; /* the field's evaluations of this advance (EvalBudget: from 0) */
    for (int k = 0; k < substeps; k++) {
        const double t_n = t0 + k * dt;
        const int rc = sdirk_step(f, b, s, dt, loads, &evals);
        if (rc != CF_FIELD_OK) return rc;
        s->t = t_n + dt;
    }
    s->t = t0 + h;
    return all_finite(s->y, 4) && all_finite(s->impulse, 3) && all_finite(s->T, 3)
               ? CF_FIELD_OK
               : CF_FIELD_NONFINITE;
}

int cf_field_summary(const cf_field *f, double theta, const double *tau_x, const double *tau_y,
                     const unsigned char *slip, double out[4], double *work,
                     unsigned char *bytes) {
    if (!field_ok(f) || tau_x == NULL || tau_y == NULL || slip == NULL || out == NULL ||
        work == NULL || bytes == NULL || !isfinite(theta))
        return CF_FIELD_BAD_INPUT;
    const size_t nx = (size_t)f->nx, ny = (size_t)f->ny, n = nx * ny;
    if (!(all_finite(tau_x, n) && all_finite(tau_y, n))) return CF_FIELD_BAD_INPUT;
    /* current(): positions and the inside mask; then the area weights w */
    double *w = work, *prod = w + n, *x = prod + n;
    for (size_t j = 0; j < nx; j++) x[j] = -f->X + ((double)j + theta) * f->dx;
    for (size_t i = 0; i < ny; i++)
        for (size_t j = 0; j < nx; j++) bytes[i * nx + j] = fabs(x[j]) < f->ell[i];
    const int rc = weights(f, x, bytes, NULL, NULL, NULL, 0.0, w, x + nx);
    if (rc != CF_FIELD_OK) return rc;
    const double total = pairwise_sum(w, n);
    for (size_t k = 0; k < n; k++) w[k] = slip[k] ? w[k] : 0.0; /* ws: the slip area's */
    const double slip_area = pairwise_sum(w, n);
    double cx = 0.0, cy = 0.0, peak = 0.0;
    for (size_t k = 0; k < n; k++) {
        const double m = hypot(tau_x[k], tau_y[k]);
        peak = m > peak ? m : peak;
    }
    if (slip_area > 0.0) {
        for (size_t i = 0; i < ny; i++)
            for (size_t j = 0; j < nx; j++) prod[i * nx + j] = w[i * nx + j] * x[j];
        cx = pairwise_sum(prod, n) / slip_area;
        for (size_t i = 0; i < ny; i++)
            for (size_t j = 0; j < nx; j++) prod[i * nx + j] = w[i * nx + j] * f->y[i];
        cy = pairwise_sum(prod, n) / slip_area;
    }
    out[0] = total > 0.0 ? (total - slip_area) / total : 0.0;
    out[1] = cx;
    out[2] = cy;
    out[3] = peak;
    return all_finite(out, 4) ? CF_FIELD_OK : CF_FIELD_NONFINITE;
}
