/* The thin-layer transient traction field (transient.py, LayerField) in C: a stage of
 * the field's step (LayerField.stage with LayerField._weights and StageField.resultant),
 * the quadrature weights, resultant and summary of a field at rest in its step
 * (LayerField.current, summary), and the body's advance on the field
 * (TransientRollingBody.advance: vx the stage unknown, Vy and Omega_z held at ratios or
 * unknowns too, Eqs. 10-11). field.c; used through ctypes by
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
    CF_FIELD_NO_ROOT = 4,   /* a stage equation without a root (StageSolveError) */
    CF_FIELD_BUDGET = 5     /* the stage solves need more evaluations than eval_limit */
};

/* The structs of these calls, cf_field (the grid and law), cf_field_stage_in and
 * cf_field_stage_out (a stage's inputs and results), cf_field_body and
 * cf_field_body_state (the body and its state), are declared once in
 * abi.py, with their fields' meanings, and come with cf_abi.h (through stepper.h): the
 * ctypes twins of field.py have the same fields from the same declarations. */

/* LayerField.stage: one stage of the field's step (StageField into out). */
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

/* ---- the body on the field: TransientRollingBody.advance ------------------------------ */
/* Scratch of cf_field_advance: doubles and bytes for an ny x nx field. */
#define CF_FIELD_ADVANCE_WORK(ny, nx) (10 * (size_t)(ny) * (size_t)(nx) + 4 * (size_t)(nx))
#define CF_FIELD_ADVANCE_BYTES(ny, nx) (3 * (size_t)(ny) * (size_t)(nx))

/* TransientRollingBody.advance(h, loads, substeps) under held loads (Fx_ex, Fy_ex,
 * My_ex, Mz_ex): substeps SDIRK2 steps of h/substeps. Anything but CF_FIELD_OK leaves
 * the state partly advanced: the caller restores it and takes the Python path. */
CF_HIDDEN int cf_field_advance(const cf_field *f, const cf_field_body *b, cf_field_body_state *s,
                               double h, const double loads[4], int substeps);

#endif
