/* The FMI 3.0 co-simulation layer of the native FMU (fmu_build --native --fmi3): a thin
 * translation of each FMI 3.0 call onto the FMI 2.0 entry point of fmu2.c, compiled into
 * the same library (this file includes fmu2.c: one translation unit). Every rule of the
 * FMU (the checks of a value, of a call, of a step, the messages, the FMU state and its
 * serialization) lives in fmu2.c once; here are only the shapes FMI 3.0 changed:
 * - the instance is a small wrapper holding fmu2.c's instance, the importer's instance
 *   environment and its log callback; fmu2.c gets a logger that formats its message and
 *   hands the text to fmi3's logMessage, and calloc/free as its memory callbacks;
 * - the resource path (a native path in FMI 3.0) becomes the file URI fmi2Instantiate
 *   reads;
 * - fmi3EnterInitializationMode = fmi2SetupExperiment + fmi2EnterInitializationMode;
 * - fmi3DoStep = fmi2DoStep; eventHandlingNeeded, terminateSimulation and earlyReturn are
 *   always false (no event mode, the FMU never ends a simulation, no early return),
 *   lastSuccessfulTime is fmi2LastSuccessfulTime;
 * - the independent variable time (FMI 3.0 requires one) has the value reference after
 *   the model's (CF3_VR_TIME) and is read as fmi2LastSuccessfulTime;
 * - Float64 = Real, Int32 = Integer, Boolean converted, String as is; every other type
 *   has no variable here; statuses map one to one;
 * - fmi3GetAdjointDerivative: seed^T J from fmi2GetDirectionalDerivative's columns.
 * The functions FMI 3.0 defines that this FMU does not provide (model exchange, scheduled
 * execution, event mode, clocks, configuration mode) answer fmi3Error with a logged
 * message. fmu2.c's functions stay internal to this library: fmi2Functions.h, which marks
 * them exported, is kept out (its types come in) and they are compiled with hidden
 * visibility, so the binary exports the FMI 3.0 functions only. */
#include <ctype.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

/* fmu2.c without fmi2Functions.h: its types, its version string, no exported names */
#define fmi2Functions_h
#include "fmi2FunctionTypes.h"
#include "fmi2TypesPlatform.h"
#define fmi2Version "2.0"
#if defined(__GNUC__)
#pragma GCC visibility push(hidden)
#endif
#include "fmu2.c"
#if defined(__GNUC__)
#pragma GCC visibility pop
#endif

#define CF3_VR_TIME ((fmi3ValueReference)CF_N_VARS)

typedef struct {
    fmi2Component c; /* fmu2.c's instance, doing the work */
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
} cf3_instance;

_Static_assert(sizeof(fmi2Integer) == sizeof(fmi3Int32), "Int32 is fmi2Integer");
_Static_assert(sizeof(fmi2Byte) == sizeof(fmi3Byte), "a byte is a byte");

static fmi3Status st3(fmi2Status s) {
    switch (s) {
    case fmi2OK: return fmi3OK;
    case fmi2Warning: return fmi3Warning;
    case fmi2Discard: return fmi3Discard;
    case fmi2Fatal: return fmi3Fatal;
    default: return fmi3Error; /* fmi2Error; fmi2Pending is never answered */
    }
}

static const char *category3(fmi3Status s) {
    switch (s) {
    case fmi3Warning: return "logStatusWarning";
    case fmi3Discard: return "logStatusDiscard";
    case fmi3Error: return "logStatusError";
    case fmi3Fatal: return "logStatusFatal";
    default: return "logAll";
    }
}

/* fmu2.c's logger: its format and arguments become the text of fmi3's logMessage */
static void logger3(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                    fmi2String category, fmi2String fmt, ...) {
    const cf3_instance *W = (const cf3_instance *)env;
    (void)name;
    if (W == NULL || W->log == NULL || fmt == NULL) return;
    char msg[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    W->log(W->env, st3(status), category, msg);
}

/* a refusal of this layer's own, in the words fmu2.c would use */
static fmi3Status refuse(const cf3_instance *W, const char *fmt, ...) {
    if (W == NULL || W->log == NULL) return fmi3Error;
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    W->log(W->env, fmi3Error, category3(fmi3Error), msg);
    return fmi3Error;
}

static fmi3Status worst(fmi3Status a, fmi3Status b) { return a > b ? a : b; }

/* the file URI of a native resource path (FMI 3.0) for fmi2Instantiate; NULL for none */
static char *resource_uri(const char *path) {
    if (path == NULL) return NULL;
    const size_t n = strlen(path);
    char *uri = (char *)calloc(3 * n + 16, 1);
    if (uri == NULL) return NULL;
    size_t k = (size_t)sprintf(uri, "file://");
    if (path[0] != '/') uri[k++] = '/'; /* a drive letter: file:///C:/ */
    for (size_t i = 0; i < n; i++) {
        const unsigned char ch = (unsigned char)path[i];
        if (ch == '\\') uri[k++] = '/';
        else if (isalnum(ch) || strchr("/-._~:", ch)) uri[k++] = (char)ch;
        else k += (size_t)sprintf(uri + k, "%%%02X", ch);
    }
    return uri;
}

#define INST3()                                                                          \
    cf3_instance *W = (cf3_instance *)instance;                                          \
    if (W == NULL) return fmi3Error

/* the values come one per value reference: every variable is a scalar */
#define SCALARS(fn)                                                                      \
    if (nValues != nValueReferences)                                                     \
    return refuse(W, "%s: %zu values for %zu value references (every variable is a "   \
                  "scalar)", fn, nValues, nValueReferences)

/* ---- common functions ------------------------------------------------------------------ */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    INST3();
    return st3(fmi2SetDebugLogging(W->c, loggingOn, nCategories, categories));
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    /* no early return and no intermediate update: nothing to do for those requests */
    (void)earlyReturnAllowed, (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables, (void)intermediateUpdate;
    cf3_instance probe = {NULL, instanceEnvironment, logMessage};
    if (eventModeUsed) {
        refuse(&probe, "fmi3InstantiateCoSimulation: this FMU has no event mode "
               "(hasEventMode is false)");
        return NULL;
    }
    cf3_instance *W = (cf3_instance *)calloc(1, sizeof *W);
    char *uri = resource_uri(resourcePath);
    if (W == NULL || (resourcePath != NULL && uri == NULL)) {
        free(W);
        free(uri);
        refuse(&probe, "fmi3InstantiateCoSimulation: out of memory");
        return NULL;
    }
    *W = probe;
    const fmi2CallbackFunctions cb = {logger3, calloc, free, NULL, W};
    W->c = fmi2Instantiate(instanceName, fmi2CoSimulation, instantiationToken, uri, &cb,
                           visible, loggingOn);
    free(uri);
    if (W->c == NULL) { /* refused, logged by fmi2Instantiate */
        free(W);
        return NULL;
    }
    return W;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName,
                                          fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn;
    const cf3_instance probe = {NULL, instanceEnvironment, logMessage};
    refuse(&probe, "fmi3InstantiateModelExchange: this FMU is for co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    const cf3_instance probe = {NULL, instanceEnvironment, logMessage};
    refuse(&probe, "fmi3InstantiateScheduledExecution: this FMU is for co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    cf3_instance *W = (cf3_instance *)instance;
    if (W == NULL) return;
    fmi2FreeInstance(W->c);
    free(W);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    INST3();
    const fmi3Status s = st3(fmi2SetupExperiment(W->c, toleranceDefined, tolerance, startTime,
                                                 stopTimeDefined, stopTime));
    if (s > fmi3Warning) return s;
    return worst(s, st3(fmi2EnterInitializationMode(W->c)));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    INST3();
    return st3(fmi2ExitInitializationMode(W->c));
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    INST3();
    return refuse(W, "fmi3EnterEventMode: this FMU has no event mode (hasEventMode is false)");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    INST3();
    return st3(fmi2Terminate(W->c));
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    INST3();
    return st3(fmi2Reset(W->c));
}

/* ---- getting and setting values -------------------------------------------------------- */
static int has_time(const fmi3ValueReference vr[], size_t n) {
    for (size_t i = 0; i < n && vr != NULL; i++)
        if (vr[i] == CF3_VR_TIME) return 1;
    return 0;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetFloat64");
    if (!has_time(valueReferences, nValueReferences))
        return st3(fmi2GetReal(W->c, valueReferences, nValueReferences, values));
    fmi3Status s = fmi3OK; /* one at a time: time is fmi2LastSuccessfulTime */
    for (size_t i = 0; i < nValueReferences && s < fmi3Error; i++)
        s = worst(s, st3(valueReferences[i] == CF3_VR_TIME
                             ? fmi2GetRealStatus(W->c, fmi2LastSuccessfulTime, &values[i])
                             : fmi2GetReal(W->c, &valueReferences[i], 1, &values[i])));
    return s;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues) {
    INST3();
    SCALARS("fmi3SetFloat64");
    if (has_time(valueReferences, nValueReferences))
        return refuse(W, "fmi3SetFloat64: time (value reference %u) is the independent "
                      "variable: doStep advances it", (unsigned)CF3_VR_TIME);
    return st3(fmi2SetReal(W->c, valueReferences, nValueReferences, values));
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int32 values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetInt32");
    return st3(fmi2GetInteger(W->c, valueReferences, nValueReferences, (fmi2Integer *)values));
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int32 values[], size_t nValues) {
    INST3();
    SCALARS("fmi3SetInt32");
    return st3(fmi2SetInteger(W->c, valueReferences, nValueReferences,
                              (const fmi2Integer *)values));
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Boolean values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetBoolean");
    if (nValueReferences > 0 && (valueReferences == NULL || values == NULL)) return fmi3Error;
    for (size_t i = 0; i < nValueReferences; i++) { /* fmi3Boolean is bool, fmi2's int */
        fmi2Boolean b = fmi2False;
        const fmi3Status s = st3(fmi2GetBoolean(W->c, &valueReferences[i], 1, &b));
        if (s > fmi3Warning) return s;
        values[i] = b != fmi2False;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Boolean values[], size_t nValues) {
    INST3();
    SCALARS("fmi3SetBoolean");
    if (nValueReferences > 0 && (valueReferences == NULL || values == NULL)) return fmi3Error;
    for (size_t i = 0; i < nValueReferences; i++) {
        const fmi2Boolean b = values[i] ? fmi2True : fmi2False;
        const fmi3Status s = st3(fmi2SetBoolean(W->c, &valueReferences[i], 1, &b));
        if (s > fmi3Warning) return s;
    }
    return fmi3OK;
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, fmi3String values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetString");
    return st3(fmi2GetString(W->c, valueReferences, nValueReferences, values));
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const fmi3String values[], size_t nValues) {
    INST3();
    SCALARS("fmi3SetString");
    return st3(fmi2SetString(W->c, valueReferences, nValueReferences, values));
}

/* the types this FMU has no variable of: an empty call is fine, any value reference is
 * refused in fmu2.c's words (vr_ok) */
static fmi3Status no_variable(const cf3_instance *W, const char *fn,
                              const fmi3ValueReference vr[], size_t n) {
    if (n == 0) return fmi3OK;
    return refuse(W, "%s: value reference %u is not a variable of this type", fn,
                  vr ? (unsigned)vr[0] : 0u);
}

#define NO_VARIABLE(NAME, T, CONST)                                                        \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference valueReferences[],     \
                    size_t nValueReferences, CONST T values[], size_t nValues) {            \
        INST3();                                                                           \
        (void)values, (void)nValues;                                                       \
        return no_variable(W, #NAME, valueReferences, nValueReferences);                   \
    }
NO_VARIABLE(fmi3GetFloat32, fmi3Float32, )
NO_VARIABLE(fmi3GetInt8, fmi3Int8, )
NO_VARIABLE(fmi3GetUInt8, fmi3UInt8, )
NO_VARIABLE(fmi3GetInt16, fmi3Int16, )
NO_VARIABLE(fmi3GetUInt16, fmi3UInt16, )
NO_VARIABLE(fmi3GetUInt32, fmi3UInt32, )
NO_VARIABLE(fmi3GetInt64, fmi3Int64, )
NO_VARIABLE(fmi3GetUInt64, fmi3UInt64, )
NO_VARIABLE(fmi3SetFloat32, fmi3Float32, const)
NO_VARIABLE(fmi3SetInt8, fmi3Int8, const)
NO_VARIABLE(fmi3SetUInt8, fmi3UInt8, const)
NO_VARIABLE(fmi3SetInt16, fmi3Int16, const)
NO_VARIABLE(fmi3SetUInt16, fmi3UInt16, const)
NO_VARIABLE(fmi3SetUInt32, fmi3UInt32, const)
NO_VARIABLE(fmi3SetInt64, fmi3Int64, const)
NO_VARIABLE(fmi3SetUInt64, fmi3UInt64, const)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                         size_t nValues) {
    INST3();
    (void)valueSizes, (void)values, (void)nValues;
    return no_variable(W, "fmi3GetBinary", valueReferences, nValueReferences);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) {
    INST3();
    (void)valueSizes, (void)values, (void)nValues;
    return no_variable(W, "fmi3SetBinary", valueReferences, nValueReferences);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) {
    INST3();
    (void)values;
    return no_variable(W, "fmi3GetClock", valueReferences, nValueReferences);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) {
    INST3();
    (void)values;
    return no_variable(W, "fmi3SetClock", valueReferences, nValueReferences);
}

/* ---- what this FMU does not provide ---------------------------------------------------- */
#define NOT_PROVIDED(fn, why) return refuse(W, "%s: not provided (%s)", fn, why)
#define NO_CLOCKS "this FMU has no clocks"
#define NO_ME "this FMU is for co-simulation only"
#define NO_EVENTS "this FMU has no event mode (hasEventMode is false)"

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    INST3();
    (void)valueReference, (void)nDependencies;
    NOT_PROVIDED("fmi3GetNumberOfVariableDependencies",
                 "the dependencies are those of the model description's ModelStructure");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    INST3();
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    NOT_PROVIDED("fmi3GetVariableDependencies",
                 "the dependencies are those of the model description's ModelStructure");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    INST3();
    NOT_PROVIDED("fmi3EnterConfigurationMode", "this FMU has no structural parameter");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    INST3();
    NOT_PROVIDED("fmi3ExitConfigurationMode", "this FMU has no structural parameter");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                  size_t n, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    INST3();
    (void)vr, (void)n, (void)intervals, (void)qualifiers;
    NOT_PROVIDED("fmi3GetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t n, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    INST3();
    (void)vr, (void)n, (void)counters, (void)resolutions, (void)qualifiers;
    NOT_PROVIDED("fmi3GetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                               fmi3Float64 shifts[]) {
    INST3();
    (void)vr, (void)n, (void)shifts;
    NOT_PROVIDED("fmi3GetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    INST3();
    (void)vr, (void)n, (void)counters, (void)resolutions;
    NOT_PROVIDED("fmi3GetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                  size_t n, const fmi3Float64 intervals[]) {
    INST3();
    (void)vr, (void)n, (void)intervals;
    NOT_PROVIDED("fmi3SetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t n, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    INST3();
    (void)vr, (void)n, (void)counters, (void)resolutions;
    NOT_PROVIDED("fmi3SetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                               const fmi3Float64 shifts[]) {
    INST3();
    (void)vr, (void)n, (void)shifts;
    NOT_PROVIDED("fmi3SetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    INST3();
    (void)vr, (void)n, (void)counters, (void)resolutions;
    NOT_PROVIDED("fmi3SetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    INST3();
    NOT_PROVIDED("fmi3EvaluateDiscreteStates", NO_EVENTS);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    INST3();
    (void)discreteStatesNeedUpdate, (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged, (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined, (void)nextEventTime;
    NOT_PROVIDED("fmi3UpdateDiscreteStates", NO_EVENTS);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    INST3();
    NOT_PROVIDED("fmi3EnterContinuousTimeMode", NO_ME);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation) {
    INST3();
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    NOT_PROVIDED("fmi3CompletedIntegratorStep", NO_ME);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    INST3();
    (void)time;
    NOT_PROVIDED("fmi3SetTime", NO_ME);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    INST3();
    (void)continuousStates, (void)nContinuousStates;
    NOT_PROVIDED("fmi3SetContinuousStates", NO_ME);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    INST3();
    (void)derivatives, (void)nContinuousStates;
    NOT_PROVIDED("fmi3GetContinuousStateDerivatives", NO_ME);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    INST3();
    (void)eventIndicators, (void)nEventIndicators;
    NOT_PROVIDED("fmi3GetEventIndicators", NO_ME);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    INST3();
    (void)continuousStates, (void)nContinuousStates;
    NOT_PROVIDED("fmi3GetContinuousStates", NO_ME);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    INST3();
    (void)nominals, (void)nContinuousStates;
    NOT_PROVIDED("fmi3GetNominalsOfContinuousStates", NO_ME);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    INST3();
    (void)nEventIndicators;
    NOT_PROVIDED("fmi3GetNumberOfEventIndicators", NO_ME);
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    INST3();
    (void)nContinuousStates;
    NOT_PROVIDED("fmi3GetNumberOfContinuousStates", NO_ME);
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    INST3();
    NOT_PROVIDED("fmi3EnterStepMode", NO_EVENTS);
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    INST3();
    (void)clockReference, (void)activationTime;
    NOT_PROVIDED("fmi3ActivateModelPartition", "this FMU is for co-simulation only");
}

/* ---- FMU state: one to one -------------------------------------------------------------- */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    INST3();
    return st3(fmi2GetFMUstate(W->c, FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    INST3();
    return st3(fmi2SetFMUstate(W->c, FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    INST3();
    return st3(fmi2FreeFMUstate(W->c, FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                      size_t *size) {
    INST3();
    return st3(fmi2SerializedFMUstateSize(W->c, FMUState, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size) {
    INST3();
    return st3(fmi2SerializeFMUstate(W->c, FMUState, (fmi2Byte *)serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState) {
    INST3();
    return st3(fmi2DeSerializeFMUstate(W->c, (const fmi2Byte *)serializedState, size,
                                       FMUState));
}

/* ---- derivatives ----------------------------------------------------------------------- */
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    INST3();
    if (nSeed != nKnowns || nSensitivity != nUnknowns)
        return refuse(W, "fmi3GetDirectionalDerivative: %zu seeds for %zu knowns, %zu "
                      "sensitivities for %zu unknowns (every variable is a scalar)", nSeed,
                      nKnowns, nSensitivity, nUnknowns);
    return st3(fmi2GetDirectionalDerivative(W->c, unknowns, nUnknowns, knowns, nKnowns, seed,
                                            sensitivity));
}

/* seed^T J: for each known, the column of J along it (fmi2GetDirectionalDerivative with a
 * unit direction) against the seed */
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    INST3();
    if (nSeed != nUnknowns || nSensitivity != nKnowns)
        return refuse(W, "fmi3GetAdjointDerivative: %zu seeds for %zu unknowns, %zu "
                      "sensitivities for %zu knowns (every variable is a scalar)", nSeed,
                      nUnknowns, nSensitivity, nKnowns);
    if ((nUnknowns && (unknowns == NULL || seed == NULL)) ||
        (nKnowns && (knowns == NULL || sensitivity == NULL)))
        return fmi3Error;
    double *column = (double *)calloc(nUnknowns ? nUnknowns : 1, sizeof(double));
    if (column == NULL) return refuse(W, "fmi3GetAdjointDerivative: out of memory");
    const fmi2Real one = 1.0;
    fmi3Status s = fmi3OK;
    for (size_t j = 0; j < nKnowns && s < fmi3Error; j++) {
        s = worst(s, st3(fmi2GetDirectionalDerivative(W->c, unknowns, nUnknowns, &knowns[j],
                                                      1, &one, column)));
        double sum = 0.0;
        for (size_t i = 0; i < nUnknowns; i++) sum += seed[i] * column[i];
        sensitivity[j] = sum;
    }
    free(column);
    return s;
}

/* ---- co-simulation ---------------------------------------------------------------------- */
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance,
                                    const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetOutputDerivatives");
    return st3(fmi2GetRealOutputDerivatives(W->c, valueReferences, nValueReferences,
                                            (const fmi2Integer *)orders, values));
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    INST3();
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False; /* fmi2Terminated is false */
    if (earlyReturn) *earlyReturn = fmi3False;
    const fmi3Status s = st3(fmi2DoStep(W->c, currentCommunicationPoint, communicationStepSize,
                                        noSetFMUStatePriorToCurrentPoint));
    if (lastSuccessfulTime)
        fmi2GetRealStatus(W->c, fmi2LastSuccessfulTime, lastSuccessfulTime);
    return s;
}
