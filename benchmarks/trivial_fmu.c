/* The trivial native FMU of benchmarks/bench_native.py: one state x, NIN inputs u_i
 * (vr 0 .. NIN-1), dx/dt = u_0 by explicit Euler, NOUT outputs reading x (vr NIN ..
 * NIN+NOUT-1); NIN = NOUT = 1 by default. The floor of an FMI step in C through the same
 * master, for as many values exchanged. What it does not need answers fmi2Error. */
#ifndef NIN
#define NIN 1
#endif
#ifndef NOUT
#define NOUT 1
#endif
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef struct {
    fmi2CallbackFunctions cb;
    double u[NIN], x;
} Inst;

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String n, fmi2Type t, fmi2String g, fmi2String r,
                              const fmi2CallbackFunctions *cb, fmi2Boolean v, fmi2Boolean l) {
    (void)n, (void)t, (void)g, (void)r, (void)v, (void)l;
    Inst *I = cb->allocateMemory(1, sizeof(Inst));
    if (I) I->cb = *cb;
    return I;
}

void fmi2FreeInstance(fmi2Component c) {
    Inst *I = c;
    if (I) I->cb.freeMemory(I);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean o, size_t n, const fmi2String s[]) {
    (void)c, (void)o, (void)n, (void)s;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean a, fmi2Real b, fmi2Real d,
                               fmi2Boolean e, fmi2Real f) {
    (void)c, (void)a, (void)b, (void)d, (void)e, (void)f;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c) {
    Inst *I = c;
    memset(I->u, 0, sizeof I->u);
    I->x = 0.0;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Inst *I = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= NIN + NOUT) return fmi2Error;
        v[i] = vr[i] >= NIN ? I->x : I->u[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real v[]) {
    Inst *I = c;
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= NIN) return fmi2Error;
        I->u[vr[i]] = v[i];
    }
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean p) {
    Inst *I = c;
    (void)t, (void)p;
    I->x += h * I->u[0];
    return fmi2OK;
}

#define NOT(name, ...)                                                                   \
    fmi2Status name(__VA_ARGS__) { return fmi2Error; }
NOT(fmi2GetInteger, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
NOT(fmi2GetBoolean, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
NOT(fmi2GetString, fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[])
NOT(fmi2SetInteger, fmi2Component c, const fmi2ValueReference vr[], size_t n,
    const fmi2Integer v[])
NOT(fmi2SetBoolean, fmi2Component c, const fmi2ValueReference vr[], size_t n,
    const fmi2Boolean v[])
NOT(fmi2SetString, fmi2Component c, const fmi2ValueReference vr[], size_t n,
    const fmi2String v[])
NOT(fmi2GetFMUstate, fmi2Component c, fmi2FMUstate *s)
NOT(fmi2SetFMUstate, fmi2Component c, fmi2FMUstate s)
NOT(fmi2FreeFMUstate, fmi2Component c, fmi2FMUstate *s)
NOT(fmi2SerializedFMUstateSize, fmi2Component c, fmi2FMUstate s, size_t *n)
NOT(fmi2SerializeFMUstate, fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
NOT(fmi2DeSerializeFMUstate, fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
NOT(fmi2GetDirectionalDerivative, fmi2Component c, const fmi2ValueReference a[], size_t na,
    const fmi2ValueReference b[], size_t nb, const fmi2Real d[], fmi2Real e[])
NOT(fmi2SetRealInputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
    const fmi2Integer o[], const fmi2Real v[])
NOT(fmi2GetRealOutputDerivatives, fmi2Component c, const fmi2ValueReference vr[], size_t n,
    const fmi2Integer o[], fmi2Real v[])
NOT(fmi2CancelStep, fmi2Component c)
NOT(fmi2GetStatus, fmi2Component c, const fmi2StatusKind k, fmi2Status *v)
NOT(fmi2GetRealStatus, fmi2Component c, const fmi2StatusKind k, fmi2Real *v)
NOT(fmi2GetIntegerStatus, fmi2Component c, const fmi2StatusKind k, fmi2Integer *v)
NOT(fmi2GetBooleanStatus, fmi2Component c, const fmi2StatusKind k, fmi2Boolean *v)
NOT(fmi2GetStringStatus, fmi2Component c, const fmi2StatusKind k, fmi2String *v)
