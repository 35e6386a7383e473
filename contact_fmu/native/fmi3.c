/* The FMI 3.0 co-simulation front end of the native FMU (fmu_build --native --fmi3): as
 * fmi2.c for FMI 2.0, each fmi3 function translates its arguments and status and calls
 * the instance layer (instance.h), which holds every rule, check and message; the layer
 * names FMI 3.0's calls and statuses in its messages (api "fmi3"). The fmi3Instance is
 * the cf_inst; the importer's instance environment and logMessage travel as the
 * instance's front-end bytes (cf_instantiate's env), memory is calloc/free. Here are only
 * the shapes FMI 3.0 changed:
 * - the resource path (a native path in FMI 3.0) becomes the file URI the layer reads;
 * - fmi3EnterInitializationMode = cf_setup_experiment + cf_enter_initialization_mode;
 * - fmi3DoStep = cf_do_step; eventHandlingNeeded, terminateSimulation and earlyReturn are
 *   always false (no event mode, the FMU never ends a simulation, no early return),
 *   lastSuccessfulTime is the layer's time (cf_time);
 * - the independent variable time (FMI 3.0 requires one) has the value reference after
 *   the model's (CF3_VR_TIME) and is read as cf_time;
 * - Float64 = Real, Int32 = Integer, Boolean and String as is; every other type has no
 *   variable here; values come one per value reference, except the three Float64
 *   arrays of the traction along the contact's centre line (x_centre, tau_x_centre,
 *   tau_y_centre, after time: cf_get_line) in body and contact mode on the thin-layer law;
 * - fmi3GetAdjointDerivative: seed^T J from cf_directional_derivative's columns.
 * The functions FMI 3.0 defines that this FMU does not provide (model exchange, scheduled
 * execution, event mode, clocks, configuration mode, output derivatives) answer
 * fmi3Error with a logged message. */
#include <ctype.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cf_messages.h"
#include "fmi3Functions.h"
#include "instance.h"

#define CF3_VR_TIME ((fmi3ValueReference)cf_n_variables())

_Static_assert(sizeof(fmi3Int32) == sizeof(int), "Int32 is the layer's int");
_Static_assert(sizeof(fmi3Byte) == 1, "a byte is a byte");
_Static_assert(sizeof(fmi3ValueReference) == sizeof(unsigned), "value references");

/* cf_status and fmi3Status share their values (OK 0 ... Fatal 4) */
static fmi3Status st(cf_status s) { return (fmi3Status)s; }

/* ---- the importer's callbacks for the instance (env: a cf3_env) ---------------------- */
typedef struct {
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
} cf3_env;

static void log_fmi3(void *env, const char *instance, int status, const char *category,
                     const char *message) {
    const cf3_env *e = (const cf3_env *)env;
    (void)instance; /* FMI 3.0's logMessage has no instance name: the environment is it */
    if (e->log != NULL) e->log(e->env, (fmi3Status)status, category, message);
}

static void *alloc_fmi3(void *env, size_t n, size_t size) {
    (void)env;
    return calloc(n, size);
}

static void release_fmi3(void *env, void *p) {
    (void)env;
    free(p);
}

static const cf_callbacks CALLBACKS = {log_fmi3, alloc_fmi3, release_fmi3};

static fmi3Status worst(fmi3Status a, fmi3Status b) { return a > b ? a : b; }

/* the file URI of a native resource path (FMI 3.0) for the layer; NULL for none */
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
    cf_inst *I = (cf_inst *)instance;                                                    \
    if (I == NULL) return fmi3Error

/* a refusal of this front end's own, logged as the layer logs its refusals */
#if defined(__GNUC__) || defined(__clang__)
__attribute__((format(printf, 2, 3)))
#endif
static fmi3Status refuse(const cf_inst *I, const char *fmt, ...) {
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cf_log(I, CF_STATUS_ERROR, "%s", msg);
    return fmi3Error;
}
#define REFUSE(...) refuse(I, __VA_ARGS__)

/* the values come one per value reference: every variable is a scalar */
#define SCALARS(fn)                                                                      \
    if (nValues != nValueReferences)                                                     \
    return REFUSE("%s: %zu values for %zu value references (every variable is a "       \
                  "scalar)", fn, nValues, nValueReferences)

/* a refused instantiation, logged before there is an instance */
static void refuse_instance(fmi3String name, fmi3InstanceEnvironment env,
                            fmi3LogMessageCallback log, const char *message) {
    cf3_env e = {env, log};
    cf_log_to(&CALLBACKS, &e, name, CF_STATUS_ERROR, "%s", message);
}

/* ---- common functions ------------------------------------------------------------------ */
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    INST3();
    (void)nCategories, (void)categories;
    cf_set_debug_logging(I, loggingOn);
    return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    /* no early return and no intermediate update: nothing to do for those requests */
    (void)visible, (void)earlyReturnAllowed, (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables, (void)intermediateUpdate;
    if (eventModeUsed) {
        refuse_instance(instanceName, instanceEnvironment, logMessage,
                        "fmi3InstantiateCoSimulation: this FMU has no event mode "
                        "(hasEventMode is false)");
        return NULL;
    }
    char *uri = resource_uri(resourcePath);
    if (resourcePath != NULL && uri == NULL) {
        refuse_instance(instanceName, instanceEnvironment, logMessage,
                        "fmi3InstantiateCoSimulation: out of memory");
        return NULL;
    }
    cf3_env env = {instanceEnvironment, logMessage}; /* copied into the instance */
    cf_inst *I = cf_instantiate("fmi3", instanceName, instantiationToken, uri, loggingOn,
                                &CALLBACKS, &env, sizeof env);
    free(uri);
    return I; /* NULL: refused, logged by cf_instantiate */
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName,
                                          fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    refuse_instance(instanceName, instanceEnvironment, logMessage,
                    "fmi3InstantiateModelExchange: this FMU is for co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    refuse_instance(instanceName, instanceEnvironment, logMessage,
                    "fmi3InstantiateScheduledExecution: this FMU is for co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { cf_free_instance((cf_inst *)instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    INST3();
    (void)toleranceDefined, (void)tolerance, (void)stopTimeDefined, (void)stopTime;
    const fmi3Status s = st(cf_setup_experiment(I, startTime));
    if (s > fmi3Warning) return s;
    return worst(s, st(cf_enter_initialization_mode(I)));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    INST3();
    return st(cf_exit_initialization_mode(I));
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    INST3();
    return REFUSE("fmi3EnterEventMode: this FMU has no event mode (hasEventMode is false)");
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    INST3();
    return st(cf_terminate(I));
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    INST3();
    return st(cf_reset(I));
}

/* ---- getting and setting values -------------------------------------------------------- */
/* What a Float64 value reference is beyond the model's variables: time (CF3_VR_TIME), one
 * of the centre line's arrays x_centre, tau_x_centre, tau_y_centre (model_description3.LINE:
 * the value references after time's, cf_line_size() values each), or a scalar of the
 * layer. One scan per call: the layer's sizes are asked once (they are another unit's). */
typedef struct {
    fmi3ValueReference time;
    size_t line_n;
} float64_map;

static float64_map float64_map_now(void) {
    const float64_map m = {CF3_VR_TIME, (size_t)cf_line_size()};
    return m;
}

/* which array of the line vr is, or -1 */
static int line_of(const float64_map *m, fmi3ValueReference vr) {
    if (m->line_n == 0 || vr <= m->time || vr > m->time + 3) return -1;
    return (int)(vr - m->time - 1);
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    INST3();
    if (nValueReferences > 0 && valueReferences == NULL) return fmi3Error;
    const float64_map m = float64_map_now();
    size_t need = 0, special = 0;
    for (size_t i = 0; i < nValueReferences; i++) {
        const fmi3ValueReference vr = valueReferences[i];
        const int line = line_of(&m, vr);
        need += line >= 0 ? m.line_n : 1;
        special += line >= 0 || vr == m.time;
    }
    if (nValues != need)
        return REFUSE("fmi3GetFloat64: %zu values for %zu value references (%zu expected: "
                      "one per scalar, %zu per array of the centre line)",
                      nValues, nValueReferences, need, m.line_n);
    if (!special) return st(cf_get_real(I, valueReferences, nValueReferences, values));
    if (values == NULL) return fmi3Error;
    fmi3Status s = fmi3OK; /* one at a time: time is the layer's, the arrays the line's */
    for (size_t i = 0, k = 0; i < nValueReferences && s < fmi3Error; i++) {
        const fmi3ValueReference vr = valueReferences[i];
        const int line = line_of(&m, vr);
        if (line >= 0) {
            s = worst(s, st(cf_get_line(I, line, &values[k])));
            k += m.line_n;
            continue;
        }
        if (vr == m.time) values[k] = cf_time(I);
        else s = worst(s, st(cf_get_real(I, &vr, 1, &values[k])));
        k++;
    }
    return s;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues) {
    INST3();
    const float64_map m = float64_map_now();
    for (size_t i = 0; valueReferences != NULL && i < nValueReferences; i++) {
        const fmi3ValueReference vr = valueReferences[i];
        if (line_of(&m, vr) >= 0)
            return REFUSE("fmi3SetFloat64: value reference %u is an output of this FMU (an "
                          "array of the centre line): it cannot be set", (unsigned)vr);
        if (vr == m.time)
            return REFUSE("fmi3SetFloat64: time (value reference %u) is the independent "
                          "variable: doStep advances it", (unsigned)vr);
    }
    SCALARS("fmi3SetFloat64");
    return st(cf_set_real(I, valueReferences, nValueReferences, values));
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int32 values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetInt32");
    return st(cf_get_integer(I, valueReferences, nValueReferences, (int *)values));
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int32 values[], size_t nValues) {
    INST3();
    SCALARS("fmi3SetInt32");
    return st(cf_set_integer(I, valueReferences, nValueReferences, (const int *)values));
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Boolean values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetBoolean");
    (void)values; /* none here: any value reference is refused */
    return st(cf_get_boolean(I, valueReferences, nValueReferences));
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Boolean values[], size_t nValues) {
    INST3();
    SCALARS("fmi3SetBoolean");
    (void)values;
    return st(cf_set_boolean(I, valueReferences, nValueReferences));
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, fmi3String values[], size_t nValues) {
    INST3();
    SCALARS("fmi3GetString");
    return st(cf_get_string(I, valueReferences, nValueReferences, values));
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const fmi3String values[], size_t nValues) {
    INST3();
    SCALARS("fmi3SetString");
    return st(cf_set_string(I, valueReferences, nValueReferences, values));
}

/* the types this FMU has no variable of: an empty call is fine, any value reference is
 * refused in the layer's words (its check of a value reference's type) */
static fmi3Status no_variable(const cf_inst *I, const char *fn, const fmi3ValueReference vr[],
                              size_t n) {
    if (n == 0) return fmi3OK;
    /* the instance layer's words (cf_messages.h): fn is "fmi3" and the call's name */
    return REFUSE(CF_MSG_VR_TYPE, "fmi3", fn + 4, vr ? (unsigned)vr[0] : 0u);
}

#define NO_VARIABLE(NAME, T, CONST)                                                        \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference valueReferences[],     \
                    size_t nValueReferences, CONST T values[], size_t nValues) {            \
        INST3();                                                                           \
        (void)values, (void)nValues;                                                       \
        return no_variable(I, #NAME, valueReferences, nValueReferences);                   \
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
    return no_variable(I, "fmi3GetBinary", valueReferences, nValueReferences);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues) {
    INST3();
    (void)valueSizes, (void)values, (void)nValues;
    return no_variable(I, "fmi3SetBinary", valueReferences, nValueReferences);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[]) {
    INST3();
    (void)values;
    return no_variable(I, "fmi3GetClock", valueReferences, nValueReferences);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[]) {
    INST3();
    (void)values;
    return no_variable(I, "fmi3SetClock", valueReferences, nValueReferences);
}

/* ---- what this FMU does not provide ---------------------------------------------------- */
#define NOT_PROVIDED(fn, why) return REFUSE("%s: not provided (%s)", fn, why)
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
    return st(cf_get_state(I, FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    INST3();
    return st(cf_set_state(I, FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    INST3();
    return st(cf_free_state(I, FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                      size_t *size) {
    INST3();
    return st(cf_serialized_size(I, FMUState, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size) {
    INST3();
    return st(cf_serialize(I, FMUState, (unsigned char *)serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState) {
    INST3();
    return st(cf_deserialize(I, (const unsigned char *)serializedState, size, FMUState));
}

/* ---- derivatives ----------------------------------------------------------------------- */
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    INST3();
    if (nSeed != nKnowns || nSensitivity != nUnknowns)
        return REFUSE("fmi3GetDirectionalDerivative: %zu seeds for %zu knowns, %zu "
                      "sensitivities for %zu unknowns (every variable is a scalar)", nSeed,
                      nKnowns, nSensitivity, nUnknowns);
    return st(cf_directional_derivative(I, unknowns, nUnknowns, knowns, nKnowns, seed,
                                        sensitivity));
}

/* seed^T J: for each known, the column of J along it (cf_directional_derivative with a
 * unit direction) against the seed */
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    INST3();
    if (nSeed != nUnknowns || nSensitivity != nKnowns)
        return REFUSE("fmi3GetAdjointDerivative: %zu seeds for %zu unknowns, %zu "
                      "sensitivities for %zu knowns (every variable is a scalar)", nSeed,
                      nUnknowns, nSensitivity, nKnowns);
    if ((nUnknowns && (unknowns == NULL || seed == NULL)) ||
        (nKnowns && (knowns == NULL || sensitivity == NULL)))
        return fmi3Error;
    double *column = (double *)calloc(nUnknowns ? nUnknowns : 1, sizeof(double));
    if (column == NULL) return REFUSE("fmi3GetAdjointDerivative: out of memory");
    const double one = 1.0;
    fmi3Status s = fmi3OK;
    for (size_t j = 0; j < nKnowns && s < fmi3Error; j++) {
        s = worst(s, st(cf_directional_derivative(I, unknowns, nUnknowns, &knowns[j], 1, &one,
                                                  column)));
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
    (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
    NOT_PROVIDED("fmi3GetOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    INST3();
    (void)noSetFMUStatePriorToCurrentPoint;
    if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False; /* never ends a simulation */
    if (earlyReturn) *earlyReturn = fmi3False;
    const fmi3Status s = st(cf_do_step(I, currentCommunicationPoint, communicationStepSize));
    if (lastSuccessfulTime) *lastSuccessfulTime = cf_time(I);
    return s;
}
