/* The binary of a pythonfmu FMU: FMI 2.0 statuses the FMI standard asks for.
 *
 * pythonfmu's binary (libpythonfmu-export, packed by fmu_build under resources/) knows
 * three answers: fmi2OK, fmi2Discard from doStep, and fmi2Fatal for any Python
 * exception, after which the Python object is gone. So a model that cannot start, a
 * refused value or FMU state and a step shortened by a cap could only answer OK (with a
 * message that fmpy shows only in debug logging) or Fatal. This library is the FMU's
 * binary in its place: it loads pythonfmu's from the FMU's resources, forwards every
 * FMI call to it, and
 *
 *   - answers the status the adapter (contact_fmu/fmu/slave.py) reports for the call:
 *     the adapter writes the worst status of the messages it logged during the call
 *     into `cell`, whose address it receives once per Python object through a reserved
 *     value reference (CF_CELL_VR, fmi2SetString; after instantiate and reset). The
 *     answer is the worse of pythonfmu's and the cell's;
 *   - hands out and takes back FMU states it knows: a pointer that is not a live state
 *     of this instance (freed, or never given) is refused with fmi2Error instead of
 *     reaching pythonfmu, which would read freed memory;
 *   - wraps serialized states in an envelope (magic, format version, the FMU's GUID,
 *     payload length, CRC-32 of the payload): bytes of another FMU, another format,
 *     truncated or altered, are refused at fmi2DeSerializeFMUstate with fmi2Error;
 *   - passes every message of status Warning or worse to the importer's logger whether
 *     debug logging is on or off (FMI 2.0: debug logging gates the debug messages, not
 *     the explanation of a call that failed). pythonfmu's logger drops every message
 *     while its debug logging is off, so pythonfmu's runs with it always on and this
 *     library's logger (shim_logger) filters: fmi2OK messages pass only in debug
 *     logging (and, when the importer named categories, only those categories).
 *
 * Linux only (pythonfmu's Windows binary is shipped as it is). No mutable globals: each
 * instance holds its own table of pythonfmu's functions (dlopen counts references).
 * dlopen/dlsym are bound to their oldest versions so that the library loads on any
 * glibc that pythonfmu's own binary loads on. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
/* the messages' wording, shared with the native FMUs (generated from fmu/messages.py) */
#include "../native/cf_messages.h"

#if defined(__x86_64__)
__asm__(".symver dlopen,dlopen@GLIBC_2.2.5");
__asm__(".symver dlsym,dlsym@GLIBC_2.2.5");
__asm__(".symver dlerror,dlerror@GLIBC_2.2.5");
#endif

/* The value reference through which the adapter learns the cell's address (no
 * variable of the model description has it). Kept in step with slave.CELL_VR. */
#define CF_CELL_VR 2147483647u
/* Where fmu_build puts pythonfmu's binary, under the resources folder. */
#define CF_INNER "/pythonfmu/linux64/libpythonfmu-export.so"
/* The text sent through CF_CELL_VR when the adapter's Python object goes (kept in step
 * with slave_core.RELEASE). */
#define CF_RELEASE "release"
#define CF_MAGIC "contact_fmu state\n"
#define CF_FORMAT 1u
#define CF_MAX_STATES 4096

/* Every FMI 2.0 co-simulation function but the two without an instance. */
#define CF_FUNCTIONS(X)                                                                  \
    X(Instantiate) X(FreeInstance) X(SetDebugLogging) X(SetupExperiment)                 \
    X(EnterInitializationMode) X(ExitInitializationMode) X(Terminate) X(Reset)           \
    X(GetReal) X(GetInteger) X(GetBoolean) X(GetString)                                  \
    X(SetReal) X(SetInteger) X(SetBoolean) X(SetString)                                  \
    X(GetFMUstate) X(SetFMUstate) X(FreeFMUstate) X(SerializedFMUstateSize)              \
    X(SerializeFMUstate) X(DeSerializeFMUstate) X(GetDirectionalDerivative)              \
    X(SetRealInputDerivatives) X(GetRealOutputDerivatives) X(DoStep) X(CancelStep)       \
    X(GetStatus) X(GetRealStatus) X(GetIntegerStatus) X(GetBooleanStatus)                \
    X(GetStringStatus)

typedef struct {
#define F(name) fmi2##name##TYPE *name;
    CF_FUNCTIONS(F)
#undef F
} inner_api;

typedef struct {
    fmi2Component inner;
    inner_api api;
    fmi2CallbackFunctions cb; /* a copy: the importer's struct need not outlive us */
    fmi2CallbackFunctions inner_cb; /* pythonfmu's: shim_logger, with this instance */
    int debug;                      /* the importer's debug logging */
    char **categories;              /* ... and its categories (none: all) */
    size_t n_categories;
    char *name;
    char *guid;
    size_t guid_len;
    int cell; /* the adapter's worst status of the current call */
    /* FMI 2.0's order of the calls that pythonfmu does not check: 0 instantiated, 1 in
     * initialisation mode, 2 initialised (exitInitializationMode answered OK); and
     * whether an exitInitializationMode failed */
    int phase, init_failed;
    fmi2FMUstate *states; /* live states handed out */
    size_t n_states, cap_states;
} shim;

static void *cf_alloc(const fmi2CallbackFunctions *cb, size_t n, size_t size) {
    if (cb != NULL && cb->allocateMemory != NULL) return cb->allocateMemory(n, size);
    return calloc(n, size);
}

static void cf_free(const fmi2CallbackFunctions *cb, void *p) {
    if (p == NULL) return;
    if (cb != NULL && cb->freeMemory != NULL) cb->freeMemory(p);
    else free(p);
}

static char *cf_strdup(const fmi2CallbackFunctions *cb, const char *s, size_t *len) {
    size_t n = s == NULL ? 0 : strlen(s);
    char *d = cf_alloc(cb, n + 1, 1);
    if (d != NULL && n) memcpy(d, s, n);
    if (len != NULL) *len = n;
    return d;
}

/* A message to the importer's logger; the text goes as an argument, never as the
 * format. */
#if defined(__GNUC__) || defined(__clang__)
__attribute__((format(printf, 4, 5)))
#endif
static void cf_log(const fmi2CallbackFunctions *cb, const char *name, fmi2Status status,
                   const char *fmt, ...) {
    char msg[1024];
    va_list ap;
    if (cb == NULL || cb->logger == NULL) return;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cb->logger(cb->componentEnvironment, name != NULL ? name : "", status,
               status >= fmi2Error ? "logStatusError" : "logStatusWarning", "%s", msg);
}

/* The logger pythonfmu's binary calls (componentEnvironment: this instance). Warnings
 * and worse always reach the importer; fmi2OK messages only in debug logging, of an
 * enabled category. pythonfmu hands over finished text in the format's place with no
 * arguments (its Fmi2Logger::debugLog), and the text can quote the user's own strings
 * (a refused String value): it goes on as the argument of "%s", never as a format. */
static void shim_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                        fmi2String category, fmi2String message, ...) {
    const shim *s = env;
    if (s == NULL || s->cb.logger == NULL || message == NULL) return;
    if (status == fmi2OK) {
        size_t i;
        if (!s->debug) return;
        for (i = 0; i < s->n_categories; i++)
            if (category != NULL && strcmp(category, s->categories[i]) == 0) break;
        if (s->n_categories && i == s->n_categories) return;
    }
    s->cb.logger(s->cb.componentEnvironment, name != NULL ? name : "", status,
                 category != NULL ? category : "", "%s", message);
}

/* The importer's debug logging and categories, kept for shim_logger. */
static fmi2Status set_debug(shim *s, fmi2Boolean on, size_t n, const fmi2String categories[]) {
    for (size_t i = 0; i < s->n_categories; i++) cf_free(&s->cb, s->categories[i]);
    cf_free(&s->cb, s->categories);
    s->categories = NULL;
    s->n_categories = 0;
    s->debug = on != fmi2False;
    if (!s->debug || n == 0 || categories == NULL) return fmi2OK;
    s->categories = cf_alloc(&s->cb, n, sizeof *s->categories);
    if (s->categories == NULL) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        s->categories[s->n_categories] = cf_strdup(&s->cb, categories[i], NULL);
        if (s->categories[s->n_categories] == NULL) return fmi2Error;
        s->n_categories++;
    }
    return fmi2OK;
}

static int hexval(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* The folder of a file URI (file:///a/b%20c or file:/a/b), percent-decoded; NULL if
 * the location is not a local file URI. */
static char *uri_path(const fmi2CallbackFunctions *cb, const char *uri) {
    const char *p;
    char *out, *o;
    if (uri == NULL || strncmp(uri, "file:", 5) != 0) return NULL;
    p = uri + 5;
    if (strncmp(p, "///", 3) == 0) p += 2;
    else if (strncmp(p, "//localhost/", 12) == 0) p += 11;
    else if (strncmp(p, "//", 2) == 0) return NULL; /* a remote host */
    out = o = cf_alloc(cb, strlen(p) + 1, 1);
    if (out == NULL) return NULL;
    for (; *p; p++) {
        int hi, lo;
        if (*p == '%' && (hi = hexval(p[1])) >= 0 && (lo = hexval(p[2])) >= 0) {
            *o++ = (char)(hi * 16 + lo);
            p += 2;
        } else {
            *o++ = *p;
        }
    }
    while (o > out + 1 && o[-1] == '/') o--;
    *o = '\0';
    return out;
}

static int load_inner(shim *s, const char *resources) {
    size_t n = strlen(resources) + sizeof CF_INNER;
    char *path = cf_alloc(&s->cb, n, 1);
    void *lib;
    if (path == NULL) return 0;
    snprintf(path, n, "%s%s", resources, CF_INNER);
    lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (lib == NULL) {
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_SHIM_LOAD, path, dlerror());
        cf_free(&s->cb, path);
        return 0;
    }
    cf_free(&s->cb, path);
/* POSIX's way to take a function from dlsym's object pointer (ISO C has no cast) */
#define F(fn)                                                                          \
    *(void **)(&s->api.fn) = dlsym(lib, "fmi2" #fn);                               \
    if (s->api.fn == NULL) {                                                           \
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_SHIM_LACKS, "fmi2" #fn);              \
        return 0;                                                                        \
    }
    CF_FUNCTIONS(F)
#undef F
    return 1;
}

/* Tell the adapter where the cell is (after every creation of its Python object). */
static fmi2Status send_cell(shim *s) {
    char text[64];
    fmi2String value = text;
    fmi2ValueReference vr = CF_CELL_VR;
    snprintf(text, sizeof text, "status cell %p", (void *)&s->cell);
    s->cell = fmi2OK;
    return s->api.SetString(s->inner, &vr, 1, &value);
}

/* Tell the adapter that its Python object is about to go (fmi2FreeInstance, fmi2Reset):
 * it frees what it holds outside Python (its C core, fmu/slave_core.py) now, not when
 * the object is collected. */
static void send_release(shim *s) {
    fmi2String value = CF_RELEASE;
    fmi2ValueReference vr = CF_CELL_VR;
    s->api.SetString(s->inner, &vr, 1, &value);
}

static fmi2Status worst(fmi2Status a, int b) {
    return b > (int)a && b <= (int)fmi2Pending ? (fmi2Status)b : a;
}

/* pythonfmu's answer st to a call, made worse by the cell's: the call is an argument, so
 * it has run (and set the cell) before the cell is read here; in worst(call, s->cell)
 * the order of the two would be unspecified */
static fmi2Status with_cell(const shim *s, fmi2Status st) { return worst(st, s->cell); }

/* ---- life cycle ------------------------------------------------------------------ */
FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType,
                                          fmi2String fmuGUID, fmi2String resourceLocation,
                                          const fmi2CallbackFunctions *functions,
                                          fmi2Boolean visible, fmi2Boolean loggingOn) {
    shim *s;
    char *resources;
    if (functions == NULL) return NULL;
    if (fmuType != fmi2CoSimulation) {
        cf_log(functions, instanceName, fmi2Error, CF_MSG_CO_SIMULATION_ONLY, (int)fmuType);
        return NULL;
    }
    s = cf_alloc(functions, 1, sizeof *s);
    if (s == NULL) return NULL;
    s->cb = *functions;
    s->inner_cb = *functions;
    s->inner_cb.logger = shim_logger;
    s->inner_cb.stepFinished = NULL; /* doStep is synchronous */
    s->inner_cb.componentEnvironment = s;
    s->debug = loggingOn != fmi2False;
    s->name = cf_strdup(functions, instanceName, NULL);
    s->guid = cf_strdup(functions, fmuGUID, &s->guid_len);
    resources = uri_path(functions, resourceLocation);
    if (resources == NULL) {
        cf_log(functions, instanceName, fmi2Error, CF_MSG_RESOURCE_URI,
               resourceLocation ? resourceLocation : "(null)");
    } else if (load_inner(s, resources)) {
        s->inner = s->api.Instantiate(instanceName, fmuType, fmuGUID, resourceLocation,
                                      &s->inner_cb, visible, fmi2True);
    }
    cf_free(functions, resources);
    if (s->inner == NULL || send_cell(s) > fmi2Warning) {
        if (s->inner != NULL) s->api.FreeInstance(s->inner);
        cf_free(functions, s->name);
        cf_free(functions, s->guid);
        cf_free(functions, s);
        return NULL;
    }
    return s;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c) {
    shim *s = c;
    fmi2CallbackFunctions cb;
    if (s == NULL) return;
    cb = s->cb;
    for (size_t i = 0; i < s->n_states; i++) s->api.FreeFMUstate(s->inner, &s->states[i]);
    send_release(s);
    s->api.FreeInstance(s->inner);
    set_debug(s, fmi2False, 0, NULL);
    cf_free(&cb, s->states);
    cf_free(&cb, s->name);
    cf_free(&cb, s->guid);
    cf_free(&cb, s);
}

/* A forwarded call answered with the worse of pythonfmu's status and the cell's. */
#define CALL(s, expr)                                                                    \
    do {                                                                                 \
        fmi2Status st_;                                                                  \
        if ((s) == NULL) return fmi2Error;                                               \
        (s)->cell = fmi2OK;                                                              \
        st_ = (expr);                                                                    \
        return worst(st_, (s)->cell);                                                    \
    } while (0)

FMI2_Export fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                                           const fmi2String categories[]) {
    shim *s = c;
    if (s == NULL) return fmi2Error;
    if (set_debug(s, on, n, categories) > fmi2Warning) {
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_OUT_OF_MEMORY, "fmi2",
               CF_CALL_NAMES[CF_CALL_SET_DEBUG_LOGGING][0]);
        return fmi2Error;
    }
    CALL(s, s->api.SetDebugLogging(s->inner, fmi2True, 0, NULL));
}

FMI2_Export fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined,
                                           fmi2Real tol, fmi2Real start,
                                           fmi2Boolean stopDefined, fmi2Real stop) {
    shim *s = c;
    CALL(s, s->api.SetupExperiment(s->inner, tolDefined, tol, start, stopDefined, stop));
}

FMI2_Export fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    shim *s = c;
    fmi2Status st;
    if (s == NULL) return fmi2Error;
    s->cell = fmi2OK;
    st = with_cell(s, s->api.EnterInitializationMode(s->inner));
    if (st <= fmi2Warning && s->phase == 0) s->phase = 1;
    return st;
}

/* The phase rules of the native FMU (contact_fmu/native/instance.c), in its words:
 * exitInitializationMode only after enterInitializationMode, terminate only once the
 * model is initialised. */
FMI2_Export fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    shim *s = c;
    fmi2Status st;
    if (s == NULL) return fmi2Error;
    if (s->phase == 0) {
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_EXIT_BEFORE_ENTER, "fmi2",
               CF_CALL_NAMES[CF_CALL_ENTER_INIT][0]);
        return fmi2Error;
    }
    s->cell = fmi2OK;
    st = with_cell(s, s->api.ExitInitializationMode(s->inner));
    s->init_failed = st > fmi2Warning;
    if (!s->init_failed) s->phase = 2;
    return st;
}

FMI2_Export fmi2Status fmi2Terminate(fmi2Component c) {
    shim *s = c;
    if (s == NULL) return fmi2Error;
    if (s->phase < 2) {
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_TERMINATE_BEFORE_INIT, "fmi2",
               s->init_failed ? CF_MSG_FAILED : CF_MSG_NOT_CALLED);
        return fmi2Error;
    }
    CALL(s, s->api.Terminate(s->inner));
}

FMI2_Export fmi2Status fmi2Reset(fmi2Component c) {
    shim *s = c;
    fmi2Status st;
    if (s == NULL) return fmi2Error;
    s->cell = fmi2OK;
    s->phase = s->init_failed = 0;
    send_release(s);
    st = s->api.Reset(s->inner); /* a new Python object: it needs the cell again */
    if (st <= fmi2Warning) st = worst(st, send_cell(s));
    return worst(st, s->cell);
}

/* ---- values ------------------------------------------------------------------------ */
#define GETSET(Name, T)                                                                  \
    FMI2_Export fmi2Status fmi2Get##Name(fmi2Component c, const fmi2ValueReference vr[], \
                                         size_t n, T value[]) {                          \
        shim *s = c;                                                                     \
        CALL(s, s->api.Get##Name(s->inner, vr, n, value));                               \
    }                                                                                    \
    FMI2_Export fmi2Status fmi2Set##Name(fmi2Component c, const fmi2ValueReference vr[], \
                                         size_t n, const T value[]) {                    \
        shim *s = c;                                                                     \
        for (size_t i = 0; s != NULL && i < n; i++)                                      \
            if (vr[i] == CF_CELL_VR) {                                                   \
                cf_log(&s->cb, s->name, fmi2Error, CF_MSG_NOT_A_VARIABLE, vr[i]);        \
                return fmi2Error;                                                        \
            }                                                                            \
        CALL(s, s->api.Set##Name(s->inner, vr, n, value));                               \
    }
GETSET(Real, fmi2Real)
GETSET(Integer, fmi2Integer)
GETSET(Boolean, fmi2Boolean)
GETSET(String, fmi2String)

/* ---- FMU states ---------------------------------------------------------------------- */
static long find_state(const shim *s, fmi2FMUstate st) {
    for (size_t i = 0; st != NULL && i < s->n_states; i++)
        if (s->states[i] == st) return (long)i;
    return -1;
}

static int keep_state(shim *s, fmi2FMUstate st) {
    if (s->n_states == s->cap_states) {
        size_t cap = s->cap_states ? 2 * s->cap_states : 16;
        fmi2FMUstate *grown;
        if (cap > CF_MAX_STATES) return 0;
        grown = cf_alloc(&s->cb, cap, sizeof *grown);
        if (grown == NULL) return 0;
        if (s->n_states) memcpy(grown, s->states, s->n_states * sizeof *grown);
        cf_free(&s->cb, s->states);
        s->states = grown;
        s->cap_states = cap;
    }
    s->states[s->n_states++] = st;
    return 1;
}

/* A new state from pythonfmu: kept, or freed again when it cannot be. */
static fmi2Status adopt(shim *s, fmi2FMUstate *state, fmi2FMUstate st, fmi2Status status) {
    if (status > fmi2Warning) return status;
    if (!keep_state(s, st)) {
        s->api.FreeFMUstate(s->inner, &st);
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_TOO_MANY_STATES, CF_MAX_STATES, "fmi2",
               CF_CALL_NAMES[CF_CALL_FREE_STATE][0]);
        return fmi2Error;
    }
    *state = st;
    return status;
}

static int live_or_refuse(shim *s, fmi2FMUstate st, cf_call call) {
    char pointer[40];
    if (find_state(s, st) >= 0) return 1;
    snprintf(pointer, sizeof pointer, "%p", st);
    cf_log(&s->cb, s->name, fmi2Error, CF_MSG_NOT_A_STATE, "fmi2", CF_CALL_NAMES[call][0],
           pointer);
    return 0;
}

/* *state given to be overwritten (FMI 2.0: a live state, or NULL for a new one): a
 * live one is freed, a new one takes its place; any other pointer is refused */
static fmi2Status release_given(shim *s, fmi2FMUstate *state, cf_call call) {
    if (*state == NULL) return fmi2OK;
    if (!live_or_refuse(s, *state, call)) return fmi2Error;
    return fmi2FreeFMUstate(s, state);
}

FMI2_Export fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    shim *s = c;
    fmi2FMUstate st = NULL;
    fmi2Status status, freed;
    if (s == NULL || state == NULL) return fmi2Error;
    if ((freed = release_given(s, state, CF_CALL_GET_STATE)) > fmi2Warning) return freed;
    s->cell = fmi2OK;
    status = with_cell(s, s->api.GetFMUstate(s->inner, &st));
    return adopt(s, state, st, status);
}

FMI2_Export fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    shim *s = c;
    if (s == NULL) return fmi2Error;
    if (!live_or_refuse(s, state, CF_CALL_SET_STATE)) return fmi2Error;
    CALL(s, s->api.SetFMUstate(s->inner, state));
}

FMI2_Export fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    shim *s = c;
    long i;
    if (s == NULL || state == NULL) return fmi2Error;
    if (*state == NULL) return fmi2OK; /* the standard: nothing to free */
    if (!live_or_refuse(s, *state, CF_CALL_FREE_STATE)) return fmi2Error;
    i = find_state(s, *state);
    s->states[i] = s->states[--s->n_states];
    s->cell = fmi2OK;
    {
        fmi2Status st = with_cell(s, s->api.FreeFMUstate(s->inner, state));
        *state = NULL;
        return st;
    }
}

/* The envelope: magic, format, GUID length and GUID, payload length, CRC-32 (all
 * integers little-endian). */
static size_t header_size(const shim *s) { return sizeof CF_MAGIC - 1 + 4 + 4 + s->guid_len + 8 + 4; }

static uint32_t crc32(const unsigned char *p, size_t n) {
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
    }
    return ~c;
}

static void put_le(unsigned char *p, uint64_t v, int n) {
    for (int i = 0; i < n; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static uint64_t get_le(const unsigned char *p, int n) {
    uint64_t v = 0;
    for (int i = n - 1; i >= 0; i--) v = (v << 8) | p[i];
    return v;
}

FMI2_Export fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state,
                                                  size_t *size) {
    shim *s = c;
    size_t inner = 0;
    fmi2Status st;
    if (s == NULL || size == NULL) return fmi2Error;
    if (!live_or_refuse(s, state, CF_CALL_STATE_SIZE)) return fmi2Error;
    s->cell = fmi2OK;
    st = with_cell(s, s->api.SerializedFMUstateSize(s->inner, state, &inner));
    if (st <= fmi2Warning) *size = header_size(s) + inner;
    return st;
}

FMI2_Export fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state,
                                             fmi2Byte bytes[], size_t size) {
    shim *s = c;
    size_t head, inner = 0;
    unsigned char *p = (unsigned char *)bytes;
    fmi2Status st;
    if (s == NULL || bytes == NULL) return fmi2Error;
    if (!live_or_refuse(s, state, CF_CALL_SERIALIZE)) return fmi2Error;
    head = header_size(s);
    s->cell = fmi2OK;
    st = with_cell(s, s->api.SerializedFMUstateSize(s->inner, state, &inner));
    if (st > fmi2Warning) return st;
    if (size != head + inner) {
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_SERIALIZE_SIZE, "fmi2",
               CF_CALL_NAMES[CF_CALL_SERIALIZE][0], size, head + inner, "fmi2",
               CF_CALL_NAMES[CF_CALL_STATE_SIZE][0]);
        return fmi2Error;
    }
    st = with_cell(s, s->api.SerializeFMUstate(s->inner, state, bytes + head, inner));
    if (st > fmi2Warning) return st;
    memcpy(p, CF_MAGIC, sizeof CF_MAGIC - 1);
    p += sizeof CF_MAGIC - 1;
    put_le(p, CF_FORMAT, 4);
    put_le(p + 4, s->guid_len, 4);
    p += 8;
    if (s->guid_len) memcpy(p, s->guid, s->guid_len);
    p += s->guid_len;
    put_le(p, inner, 8);
    put_le(p + 8, crc32((const unsigned char *)bytes + head, inner), 4);
    return st;
}

FMI2_Export fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[],
                                               size_t size, fmi2FMUstate *state) {
    shim *s = c;
    const unsigned char *p = (const unsigned char *)bytes;
    size_t head, m = sizeof CF_MAGIC - 1;
    uint64_t format, glen, inner;
    const char *why = NULL;
    char length[128];
    fmi2FMUstate st = NULL;
    fmi2Status status;
    if (s == NULL || state == NULL) return fmi2Error;
    head = header_size(s);
    if (bytes == NULL || size < m + 8 || memcmp(p, CF_MAGIC, m) != 0) {
        why = CF_MSG_NOT_SERIALIZED;
    } else if ((format = get_le(p + m, 4)) != CF_FORMAT) {
        why = CF_MSG_OTHER_VERSION;
    } else if ((glen = get_le(p + m + 4, 4)) != s->guid_len || size < head ||
               memcmp(p + m + 8, s->guid, s->guid_len) != 0) {
        why = CF_MSG_OTHER_FMU;
    } else if ((inner = get_le(p + head - 12, 8)) != size - head) {
        snprintf(length, sizeof length, CF_MSG_LENGTH_DIFFERS, CF_MSG_LENGTH_RECORDED);
        why = length;
    } else if (get_le(p + head - 4, 4) != crc32(p + head, (size_t)inner)) {
        why = CF_MSG_CHECKSUM_DIFFERS;
    }
    if (why != NULL) {
        cf_log(&s->cb, s->name, fmi2Error, CF_MSG_BYTES_REFUSED, "fmi2",
               CF_CALL_NAMES[CF_CALL_DESERIALIZE][0], size, why);
        return fmi2Error;
    }
    if ((status = release_given(s, state, CF_CALL_DESERIALIZE)) > fmi2Warning)
        return status;
    s->cell = fmi2OK;
    status = worst(s->api.DeSerializeFMUstate(s->inner, bytes + head, size - head, &st),
                   s->cell);
    return adopt(s, state, st, status);
}

/* ---- co-simulation -------------------------------------------------------------------- */
FMI2_Export fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h,
                                  fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    shim *s = c;
    CALL(s, s->api.DoStep(s->inner, t, h, noSetFMUStatePriorToCurrentPoint));
}

FMI2_Export fmi2Status fmi2CancelStep(fmi2Component c) {
    shim *s = c;
    CALL(s, s->api.CancelStep(s->inner));
}

FMI2_Export fmi2Status fmi2GetDirectionalDerivative(fmi2Component c,
                                                    const fmi2ValueReference vu[], size_t nu,
                                                    const fmi2ValueReference vk[], size_t nk,
                                                    const fmi2Real dk[], fmi2Real du[]) {
    shim *s = c;
    CALL(s, s->api.GetDirectionalDerivative(s->inner, vu, nu, vk, nk, dk, du));
}

FMI2_Export fmi2Status fmi2SetRealInputDerivatives(fmi2Component c,
                                                   const fmi2ValueReference vr[], size_t n,
                                                   const fmi2Integer order[],
                                                   const fmi2Real value[]) {
    shim *s = c;
    CALL(s, s->api.SetRealInputDerivatives(s->inner, vr, n, order, value));
}

FMI2_Export fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c,
                                                    const fmi2ValueReference vr[], size_t n,
                                                    const fmi2Integer order[],
                                                    fmi2Real value[]) {
    shim *s = c;
    CALL(s, s->api.GetRealOutputDerivatives(s->inner, vr, n, order, value));
}

#define STATUS(Name, T)                                                                  \
    FMI2_Export fmi2Status fmi2Get##Name(fmi2Component c, const fmi2StatusKind k,        \
                                         T *value) {                                     \
        shim *s = c;                                                                     \
        CALL(s, s->api.Get##Name(s->inner, k, value));                                   \
    }
STATUS(Status, fmi2Status)
STATUS(RealStatus, fmi2Real)
STATUS(IntegerStatus, fmi2Integer)
STATUS(BooleanStatus, fmi2Boolean)
STATUS(StringStatus, fmi2String)
