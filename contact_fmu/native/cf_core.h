/* The adapter's checks of a value and of a doStep call, written once for both front
 * ends of the compiled step: the CPython binding of the pythonfmu FMU (fmi.c, which
 * includes this file) and the instance layer of the native FMU (instance.c, through
 * stepper.h). Each is the rule of contact_fmu/fmu/slave.py (and variables.Var.check);
 * the messages are the callers': fmi.c hands a refused call to the Python adapter,
 * which words it, instance.c words it the same (tests/test_native_fmu.py compares them).
 * The step's own checks (the load limit, the cap on internal steps, the outputs'
 * range and finiteness) are stepper.c's, next to the step (cf_body_check). */
#ifndef CF_CORE_H
#define CF_CORE_H

#include <float.h>
#include <math.h>

/* Var.check's verdict on a Real's double against its declared range [lo, hi] (lo
 * excluded when open_lo; -inf and inf where none is declared): finiteness first, then
 * the lower bound, then the upper one (the order of the message's requirement) */
enum { CF_VALUE_OK, CF_VALUE_NONFINITE, CF_VALUE_BELOW, CF_VALUE_ABOVE };

static inline int cf_value_check(double x, double lo, double hi, int open_lo) {
    if (!isfinite(x)) return CF_VALUE_NONFINITE;
    if (open_lo ? !(lo < x) : x < lo) return CF_VALUE_BELOW;
    if (x > hi) return CF_VALUE_ABOVE;
    return CF_VALUE_OK;
}

/* slave._do_step: a communication step size h in (0, inf) (NaN is not) */
static inline int cf_step_size_ok(double h) { return h > 0.0 && h <= DBL_MAX; }

/* slave._do_step: t, finite, is the FMU's time to rtol (call_state.TIME_RTOL, 64 ulp) of
 * max(|t|, |time|) */
static inline int cf_time_ok(double t, double time, double rtol) {
    return isfinite(t) && fabs(t - time) <= rtol * fmax(fabs(t), fabs(time));
}

#endif
