/* A driver of field.c's functions for tests/test_native_field.py, built with the
 * sanitizers (AddressSanitizer, UBSan with float-to-int overflow, no recovery): random
 * and extreme stage inputs on the fig12_transient grid (32 x 16, the thin-layer law of
 * Section 4 at P = 1000 N), damaged field structs and NULL pointers; every eighth call
 * also advances the body on the field (cf_field_advance) from a random state under
 * random loads. Every call must answer one of field.h's codes, and an OK call serves
 * finite numbers and 0/1 masks.
 *
 *   native_field_driver SEED CALLS
 *   ->  "ok N bad_input N range N nonfinite N advance_ok N advance_declined N"
 * (exit status 1 on a broken promise, with the call printed). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "field.h"

#define NX 32
#define NY 16
#define N (NX * NY)

static unsigned long long rng_state;

static unsigned long long next(void) { /* xorshift64* */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ULL;
}

static double uniform(void) { return (double)(next() >> 11) * (1.0 / 9007199254740992.0); }

/* a value from the extremes or a plausible random one (scale: its physical size) */
static double pick(double scale) {
    static const double extremes[] = {0.0, -0.0, 5e-324, -5e-324, 1e-300, -1e-300, 1e300,
                                      -1e300, DBL_MAX, -DBL_MAX, NAN, INFINITY, -INFINITY};
    const unsigned long long n = sizeof extremes / sizeof extremes[0];
    if (next() % 16 == 0) return extremes[next() % n];
    return scale * (2.0 * uniform() - 1.0) * pow(10.0, 4.0 * uniform() - 2.0);
}

static int finite_all(const double *a, int n) {
    for (int i = 0; i < n; i++)
        if (!isfinite(a[i])) return 0;
    return 1;
}

static int masks_ok(const unsigned char *a, int n) {
    for (int i = 0; i < n; i++)
        if (a[i] > 1) return 0;
    return 1;
}

int main(int argc, char **argv) {
    if (argc != 3) return 2;
    rng_state = strtoull(argv[1], NULL, 10) * 0x9E3779B97F4A7C15ULL + 1ULL;
    const long calls = strtol(argv[2], NULL, 10);
    /* the fig12_transient contact: a1, a2, p0 of Eq. (34) at P = 1000 N */
    const double a1 = 2.5897e-3, a2 = 3.6625e-3, p0 = 6.7126e7, mu = 0.3, k = 6.4e-13;
    double y[NY], ell[NY], p_strip[NY], dy_w[NY];
    const double dphi = M_PI / NY;
    for (int i = 0; i < NY; i++) {
        const double phi = -0.5 * M_PI + (i + 0.5) * dphi;
        y[i] = a2 * sin(phi);
        ell[i] = a1 * sqrt(fmax(1.0 - (y[i] / a2) * (y[i] / a2), 0.0));
        p_strip[i] = p0 * (1.0 - (y[i] / a2) * (y[i] / a2));
        dy_w[i] = a2 * cos(phi) * dphi;
    }
    cf_field f = {NY, NX, 2.0 * a1 / NX, a1, a1, p0, mu, k, mu * p0 / (a1 * a1), 0.1,
                  y, ell, p_strip, dy_w};
    static double hat_x[N], hat_y[N], x[NX], tau_x[N], tau_y[N], w[N], work[5 * N + 3 * NX];
    static unsigned char inside[N], slip[N], ins_out[N];
    long counts[4] = {0, 0, 0, 0}, advances[5] = {0, 0, 0, 0, 0};
    for (long c = 0; c < calls; c++) {
        const double tau_scale = mu * p0 * (next() % 8 == 0 ? 1e6 : 1.0);
        for (int r = 0; r < N; r++) {
            hat_x[r] = tau_scale * (2.0 * uniform() - 1.0);
            hat_y[r] = tau_scale * (2.0 * uniform() - 1.0);
            inside[r] = (unsigned char)(next() % 2);
        }
        if (next() % 4 == 0) hat_x[next() % N] = pick(tau_scale);
        if (next() % 4 == 0) hat_y[next() % N] = pick(tau_scale);
        const double V = 5.64;
        cf_field_stage_in in = {uniform(), inside, hat_x, hat_y,
                                pick(f.dx * NX),  pick(1e-5), pick(1e-5),
                                pick(0.02 * V), pick(0.02 * V), pick(10.0),
                                pick(V), (int)(next() % 2), (int)(next() % 2)};
        cf_field_stage_out out = {0.0, 0, x, tau_x, tau_y, w, slip, ins_out, work,
                                  {0.0, 0.0, 0.0}, 0.0, {0.0}};
        cf_field g = f;
        switch (next() % 16) { /* a damaged struct now and then */
        case 0: g.nx = (int)(next() % 3) - 1; break;
        case 1: g.dx = pick(1.0); break;
        case 2: g.k = pick(1e-12); break;
        case 3: g.y = NULL; break;
        case 4: out.work = NULL; break;
        default: break;
        }
        const int rc = cf_field_stage(&g, &in, &out);
        if (rc < 0 || rc > 3) {
            printf("call %ld: code %d\n", c, rc);
            return 1;
        }
        counts[rc]++;
        if (rc == CF_FIELD_OK &&
            !(finite_all(x, NX) && finite_all(tau_x, N) && finite_all(tau_y, N) &&
              finite_all(w, N) && finite_all(out.T, 3) && isfinite(out.dTx_dvx) &&
              finite_all(out.J, 9) && masks_ok(slip, N) && masks_ok(ins_out, N) &&
              out.theta >= 0.0 && out.theta < 1.0)) {
            printf("call %ld: OK with a non-finite result (ds %g vx %g)\n", c, in.ds, in.vx);
            return 1;
        }
        /* the weights of a field at rest, and the area weights */
        const int rw = cf_field_weights(&g, x, inside, next() % 4 ? hat_x : NULL,
                                        next() % 4 ? hat_y : NULL, next() % 2 ? slip : NULL,
                                        pick(1.0), w, work);
        if (rw < 0 || rw > 3 || (rw == CF_FIELD_OK && !finite_all(w, N))) {
            printf("call %ld: weights code %d\n", c, rw);
            return 1;
        }
        if (c % 8 == 0) { /* the body on the field: cf_field_advance */
            static double sx[N], sy[N], swork[CF_FIELD_ADVANCE_WORK(NY, NX)];
            static unsigned char ss[N], sbytes[CF_FIELD_ADVANCE_BYTES(NY, NX)];
            for (int r = 0; r < N; r++) {
                sx[r] = hat_x[r];
                sy[r] = hat_y[r];
                ss[r] = (unsigned char)(next() % 2);
            }
            const double M = next() % 16 ? 1.0 : pick(1.0), eta = 2.92;
            cf_field_body b = {M, 0.05, 1.0 / (1.0 + eta), eta / (1.0 + eta),
                               M * eta / (1.0 + eta), pick(0.002), pick(1.0),
                               2.0 * mu * p0 * k / a1, 1.0 - 0.5 * sqrt(2.0), 0.5 * sqrt(2.0),
                               1e-13, 1e-9, 50};
            cf_field_body_state s = {{pick(V), pick(0.05), 0.0, 0.0}, pick(1.0), {0.0, 0.0, 0.0},
                                     uniform(), 1.0, sx, sy, ss, {0.0, 0.0, 0.0}, 0, swork,
                                     sbytes};
            const double loads[4] = {pick(300.0), pick(300.0), pick(15.0), pick(15.0)};
            const int ra = cf_field_advance(&g, &b, &s, pick(2e-5), loads, (int)(next() % 4));
            if (ra < 0 || ra > 4 ||
                (ra == CF_FIELD_OK && !(finite_all(s.y, 4) && finite_all(s.T, 3) &&
                                        finite_all(sx, N) && finite_all(sy, N)))) {
                printf("call %ld: advance code %d\n", c, ra);
                return 1;
            }
            advances[ra]++;
        }
        double S[4];
        const int rs = cf_field_summary(&g, next() % 16 ? uniform() : pick(1.0), hat_x, hat_y,
                                        slip, S, work, ins_out);
        if (rs < 0 || rs > 3 || (rs == CF_FIELD_OK && !finite_all(S, 4))) {
            printf("call %ld: summary code %d\n", c, rs);
            return 1;
        }
        double T[3];
        const int rr = cf_field_resultant(&g, x, w, hat_x, hat_y, work, T);
        if (rr < 0 || rr > 3 || (rr == CF_FIELD_OK && !finite_all(T, 3))) {
            printf("call %ld: resultant code %d\n", c, rr);
            return 1;
        }
    }
    /* NULL everywhere */
    if (cf_field_stage(NULL, NULL, NULL) != CF_FIELD_BAD_INPUT ||
        cf_field_weights(NULL, NULL, NULL, NULL, NULL, NULL, 0.0, NULL, NULL) !=
            CF_FIELD_BAD_INPUT ||
        cf_field_resultant(NULL, NULL, NULL, NULL, NULL, NULL, NULL) != CF_FIELD_BAD_INPUT) {
        printf("NULL accepted\n");
        return 1;
    }
    printf("ok %ld bad_input %ld range %ld nonfinite %ld advance_ok %ld advance_declined %ld\n",
           counts[0], counts[1], counts[2], counts[3], advances[0],
           advances[1] + advances[2] + advances[3] + advances[4]);
    return 0;
}
