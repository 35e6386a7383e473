/* The FMI 2.0 co-simulation front end of the native FMU: each fmi2 function translates
 * its arguments and status and calls the instance layer (instance.h), which holds every
 * rule, check and message. The fmi2Component is the cf_inst; the importer's callbacks
 * travel as the instance's front-end bytes (cf_instantiate's env), whence the adapters
 * below reach them. Only what FMI 2.0 alone has is answered here: the type of
 * instantiation, the status queries, input and output derivatives, cancelStep. */
#include <stddef.h>

#include "fmi2Functions.h"
#include "instance.h"

#define INST()                                                                           \
    cf_inst *I = (cf_inst *)c;                                                           \
    if (I == NULL) return fmi2Error

/* cf_status and fmi2Status share their values (OK 0 ... Fatal 4) */
static fmi2Status st(cf_status s) { return (fmi2Status)s; }

/* ---- the importer's callbacks for the instance (env: its fmi2CallbackFunctions) -------- */
static void log_fmi2(void *env, const char *instance, int status, const char *category,
                     const char *message) {
    const fmi2CallbackFunctions *f = (const fmi2CallbackFunctions *)env;
    if (f->logger != NULL) /* the message as an argument, never as the format */
        f->logger(f->componentEnvironment, instance, (fmi2Status)status, category, "%s",
                  message);
}

static void *alloc_fmi2(void *env, size_t n, size_t size) {
    return ((const fmi2CallbackFunctions *)env)->allocateMemory(n, size);
}

static void release_fmi2(void *env, void *p) {
    ((const fmi2CallbackFunctions *)env)->freeMemory(p);
}

static const cf_callbacks CALLBACKS = {log_fmi2, alloc_fmi2, release_fmi2};

/* ---- FMI 2.0 ---------------------------------------------------------------------------- */
const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    INST();
    (void)n, (void)cats;
    cf_set_debug_logging(I, on != fmi2False);
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *cb,
                              fmi2Boolean visible, fmi2Boolean logging) {
    (void)visible;
    if (cb == NULL || cb->allocateMemory == NULL || cb->freeMemory == NULL) return NULL;
    fmi2CallbackFunctions env = *cb; /* the importer's struct need not outlive the call */
    if (type != fmi2CoSimulation) {
        cf_log_to(&CALLBACKS, &env, name, CF_STATUS_ERROR,
                  "fmi2Instantiate: this FMU is for co-simulation only");
        return NULL;
    }
    return cf_instantiate("fmi2", name, guid, resources, logging != fmi2False, &CALLBACKS, &env,
                          sizeof env);
}

void fmi2FreeInstance(fmi2Component c) { cf_free_instance((cf_inst *)c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol,
                               fmi2Real start, fmi2Boolean stopDefined, fmi2Real stop) {
    INST();
    (void)tolDefined, (void)tol, (void)stopDefined, (void)stop;
    return st(cf_setup_experiment(I, start));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    INST();
    return st(cf_enter_initialization_mode(I));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    INST();
    return st(cf_exit_initialization_mode(I));
}

fmi2Status fmi2Terminate(fmi2Component c) {
    INST();
    return st(cf_terminate(I));
}

fmi2Status fmi2Reset(fmi2Component c) {
    INST();
    return st(cf_reset(I));
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    INST();
    return st(cf_get_real(I, vr, n, v));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer v[]) {
    INST();
    return st(cf_get_integer(I, vr, n, v));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean v[]) {
    INST();
    (void)v;
    return st(cf_get_boolean(I, vr, n));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         fmi2String v[]) {
    INST();
    return st(cf_get_string(I, vr, n, v));
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[]) {
    INST();
    return st(cf_set_real(I, vr, n, v));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer v[]) {
    INST();
    return st(cf_set_integer(I, vr, n, v));
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean v[]) {
    INST();
    (void)v;
    return st(cf_set_boolean(I, vr, n));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String v[]) {
    INST();
    return st(cf_set_string(I, vr, n, v));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    INST();
    (void)noSetPrior;
    return st(cf_do_step(I, t, h));
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    INST();
    cf_log(I, CF_STATUS_ERROR, "fmi2CancelStep: doStep runs synchronously; nothing to cancel");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    INST();
    (void)s, (void)v;
    cf_log(I, CF_STATUS_ERROR, "fmi2GetStatus: doStep runs synchronously; no pending status");
    return fmi2Error;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    INST();
    if (s == fmi2LastSuccessfulTime && v != NULL) {
        *v = cf_time(I);
        return fmi2OK;
    }
    cf_log(I, CF_STATUS_ERROR, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is provided");
    return fmi2Error;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    INST();
    (void)s, (void)v;
    cf_log(I, CF_STATUS_ERROR, "fmi2GetIntegerStatus: not provided");
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    INST();
    if (s == fmi2Terminated && v != NULL) {
        *v = fmi2False; /* the FMU never ends a simulation itself */
        return fmi2OK;
    }
    cf_log(I, CF_STATUS_ERROR, "fmi2GetBooleanStatus: only fmi2Terminated is provided");
    return fmi2Error;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    INST();
    (void)s, (void)v;
    cf_log(I, CF_STATUS_ERROR, "fmi2GetStringStatus: not provided");
    return fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference zr[], size_t nz,
                                        const fmi2ValueReference ur[], size_t nu,
                                        const fmi2Real du[], fmi2Real dz[]) {
    INST();
    return st(cf_directional_derivative(I, zr, nz, ur, nu, du, dz));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    INST();
    (void)vr, (void)n, (void)order, (void)v;
    cf_log(I, CF_STATUS_ERROR, "fmi2SetRealInputDerivatives: inputs are held over a step "
           "(canInterpolateInputs is false)");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[], fmi2Real v[]) {
    INST();
    (void)vr, (void)n, (void)order, (void)v;
    cf_log(I, CF_STATUS_ERROR, "fmi2GetRealOutputDerivatives: not provided "
           "(maxOutputDerivativeOrder is 0)");
    return fmi2Error;
}

/* ---- FMU state ------------------------------------------------------------------------- */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    INST();
    return st(cf_get_state(I, state));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    INST();
    return st(cf_set_state(I, state));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    INST();
    return st(cf_free_state(I, state));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    INST();
    return st(cf_serialized_size(I, state, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte out[],
                                 size_t size) {
    INST();
    return st(cf_serialize(I, state, (unsigned char *)out, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte in[], size_t size,
                                   fmi2FMUstate *state) {
    INST();
    return st(cf_deserialize(I, (const unsigned char *)in, size, state));
}
