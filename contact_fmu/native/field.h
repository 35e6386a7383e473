/* The thin-layer transient traction field (transient.py, LayerField) in C: a stage of
 * the field's step (LayerField.stage with LayerField._weights and StageField.resultant),
 * the quadrature weights, resultant and summary of a field at rest in its step
 * (LayerField.current, summary), and the body's advance on the field where vx is the
 * only stage unknown (TransientRollingBody.advance). field.c; used through ctypes by
 * contact_fmu/native/field.py, built into the kernel library with stepper.c (the same
 * flags: no contraction into fused multiply-adds, CF_HIDDEN but for CF_KERNEL_EXPORT). */
#ifndef CF_FIELD_H
#define CF_FIELD_H

#include "stepper.h"

/* What a call answers. Anything but CF_FIELD_OK leaves the outputs undefined and the
 * caller takes the Python path (the reference), which words the error, if any. */
enum {
    CF_FIELD_OK = 0,
    CF_FIELD_BAD_INPUT = 1, /* a NULL pointer, a grid below 2 x 1, a non-finite or
                               non-positive constant, a non-finite stage input */
    CF_FIELD_RANGE = 2,     /* the stage moves the lattice by more than CF_FIELD_SHIFT_MAX
                               columns (its index would not fit): Python's integers do */
    CF_FIELD_NONFINITE = 3, /* a result overflowed (a huge finite input): not served */
    CF_FIELD_NO_ROOT = 4    /* a stage equation without a root (StageSolveError) */
};

/* Largest |shift| (columns) a stage may move the lattice by: far beyond any grid (a
 * shift of nx columns or more already empties it), small enough for any index. */
#define CF_FIELD_SHIFT_MAX 1e9

/* The field's grid and its law (LayerField: nx cells of dx over the lattice's
 * half-extent X, ny strips at y; law a1, p0, mu, k = kb + ks). Per strip: ell = l(y)
 * (Eq. 37), p_strip = p0 (1 - y^2/a2^2) (p at x = 0), dy_w the scaled strip width
 * (LayerField._update_contact). c0 = mu p0/a1^2 (mu p = c0 (l^2 - x^2), Eq. 33). */
typedef struct {
    int ny, nx;
    double dx, X, a1, p0, mu, k, c0;
    double min_speed_fraction; /* transient.MIN_SPEED_FRACTION */
    const double *y, *ell, *p_strip, *dy_w; /* (ny) */
} cf_field;

/* A stage's inputs (LayerField.stage's arguments): the base of the step (theta, the
 * inside mask, ny x nx row major, bytes 0/1), tau_hat in base indexing, the distance
 * rolled ds (m), elapsed and h_own (s), the rigid slip (vx, vy) (m/s), phi = Omega_z
 * (rad/s), Vx (m/s); midpath and jacobian as in LayerField.stage (0 or 1). */
typedef struct {
    double theta;
    const unsigned char *inside;
    const double *hat_x, *hat_y;
    double ds, elapsed, h_own, vx, vy, phi, Vx;
    int midpath, jacobian;
} cf_field_stage_in;

/* A stage's results (StageField): theta and shift, column positions x (nx), traction,
 * weights (ny x nx), the slip (slip & inside) and inside masks (bytes 0/1), the
 * resultant T = (Tx, Ty, Mz), dTx/dvx and (with jacobian) J = d(Tx, Ty, Mz)/d(vx, vy,
 * Omega_z), 3 x 3 row major. work: scratch of 5 ny nx + 3 nx doubles. */
typedef struct {
    double theta;
    long long shift;
    double *x, *tau_x, *tau_y, *w;
    unsigned char *slip, *inside;
    double *work;
    double T[3];
    double dTx_dvx;
    double J[9];
} cf_field_stage_out;

CF_HIDDEN int cf_field_stage(const cf_field *f, const cf_field_stage_in *in,
                             cf_field_stage_out *out);
/* LayerField._weights: w (ny x nx) at positions x (nx) for the masks inside and slip and
 * the traction (tau_x, tau_y), the leading edge by sign (> 0: +l, < 0: -l, 0: none);
 * tau_x = tau_y = slip = NULL: area weights. work: scratch of 3 nx doubles. */
CF_HIDDEN int cf_field_weights(const cf_field *f, const double *x, const unsigned char *inside,
                               const double *tau_x, const double *tau_y,
                               const unsigned char *slip, double sign, double *w,
                               double *work);
/* StageField.resultant: T = (Tx, Ty, Mz) of the traction with weights w at positions x;
 * work: scratch of ny nx doubles. */
CF_HIDDEN int cf_field_resultant(const cf_field *f, const double *x, const double *w,
                                 const double *tau_x, const double *tau_y, double *work,
                                 double T[3]);

/* LayerField.summary of the field at rest at theta (tau_x, tau_y, slip: ny x nx):
 * out = (adhesion fraction, slip-area centroid x, y (m), peak |tau| (Pa)); work:
 * scratch of 2 ny nx + 4 nx doubles, bytes: of ny nx. */
CF_HIDDEN int cf_field_summary(const cf_field *f, double theta, const double *tau_x,
                               const double *tau_y, const unsigned char *slip, double out[4],
                               double *work, unsigned char *bytes);

/* ---- the body on the field: TransientRollingBody.advance, scalar path ----------------- */
/* The body (Eqs. 8-11) of a TransientRollingBody whose only stage unknown is vx: Vy and
 * Omega_z held at the ratios ry, rz to Vx (Lateral). Body: M (kg), Rx (m), A1, A2,
 * m_slip = M A2 (kg); the law's creep_full_slip; SDIRK2's gamma and a21 = 1 - gamma;
 * transient.SOLVE_RTOL, V_SCALE_FLOOR (m/s), MAX_STAGE_ITERATIONS. */
typedef struct {
    double M, Rx, A1, A2, m_slip, ry, rz, creep_full_slip, gamma, a21;
    double solve_rtol, v_scale_floor;
    int max_iterations;
} cf_field_body;

/* Scratch of cf_field_advance: doubles and bytes for an ny x nx field. */
#define CF_FIELD_ADVANCE_WORK(ny, nx) (10 * (size_t)(ny) * (size_t)(nx) + 4 * (size_t)(nx))
#define CF_FIELD_ADVANCE_BYTES(ny, nx) (3 * (size_t)(ny) * (size_t)(nx))

/* The state: y = (Vx, vx, Vy, Omega_z), t (s), the contact impulse (N s, N s, N m s),
 * the field (theta, direction, tau_x, tau_y, slip: ny x nx, advanced in place), and the
 * contact at the end of the last step (T = (Tx, Ty, Mz), sliding: no adhesion). */
typedef struct {
    double y[4], t, impulse[3];
    double theta, direction;
    double *tau_x, *tau_y;
    unsigned char *slip;
    double T[3];
    int sliding;
    double *work;         /* CF_FIELD_ADVANCE_WORK(ny, nx) doubles */
    unsigned char *bytes; /* CF_FIELD_ADVANCE_BYTES(ny, nx) */
} cf_field_body_state;

/* TransientRollingBody.advance(h, loads, substeps) under held loads (Fx_ex, Fy_ex,
 * My_ex, Mz_ex): substeps SDIRK2 steps of h/substeps. Anything but CF_FIELD_OK leaves
 * the state partly advanced: the caller restores it and takes the Python path. */
CF_HIDDEN int cf_field_advance(const cf_field *f, const cf_field_body *b, cf_field_body_state *s,
                               double h, const double loads[4], int substeps);

#endif
