/* A plain C FMI 2.0 co-simulation importer for the native FMU's tests (no Python).
 *
 *   native_importer LIB GUID IDENT run  SPEC   run a case: outputs of every step (hex)
 *   native_importer LIB GUID IDENT fuzz SPEC SEED N   N random calls with extreme values
 *   native_importer LIB GUID IDENT bench SPEC N       N steps of SPEC's rows, the case
 *                                                   repeated from its start state:
 *                                                   steps per second (the master's
 *                                                   setReal, doStep, getReal)
 *   native_importer LIB GUID IDENT states SPEC N      N FMU states held at once: got,
 *                                                   set, sized (the lookup alone) and
 *                                                   freed in shuffled orders (each
 *                                                   freed one refused after): ns per
 *                                                   get, set, size and free
 *
 * LIB is the FMU's shared library, opened with dlopen; built with -DLINKED (the
 * sanitizer build: the FMU's sources compiled into this program) the functions are
 * called directly and LIB is ignored. SPEC (text):
 *   line 1: the Real inputs' value references       "n vr..."
 *   line 2: the Real outputs' value references      "n vr..."
 *   line 3: parameters set before initialisation    "n vr value..." (values as %a)
 *   then, for "run" and "bench", one row per step: "t h u_1 ... u_n" (hex floats)
 * "run" prints each step's outputs as hex floats, one line per step; "fuzz" prints a
 * count of the statuses (and of the pointers that are no state of the instance refused,
 * "refused"); "bench" the steps per second. Exit status: 0 fine, 2 usage, 3 an FMI
 * answer not allowed (fmi2Fatal, a non-finite output served with fmi2OK, damaged bytes
 * or a pointer that is no state of the instance accepted; for "bench" any answer but
 * fmi2OK, with the call, the step and the FMU's last message on stderr).
 * FMU_RESOURCES in the environment: the resource location (a file URI) to instantiate
 * with.
 */
#include <math.h>
#include <time.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "importer_common.h"

#ifndef LINKED
#include <dlfcn.h>
#endif

typedef struct {
    fmi2InstantiateTYPE *Instantiate;
    fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetupExperimentTYPE *SetupExperiment;
    fmi2EnterInitializationModeTYPE *EnterInit;
    fmi2ExitInitializationModeTYPE *ExitInit;
    fmi2TerminateTYPE *Terminate;
    fmi2ResetTYPE *Reset;
    fmi2SetRealTYPE *SetReal;
    fmi2GetRealTYPE *GetReal;
    fmi2DoStepTYPE *DoStep;
    fmi2GetFMUstateTYPE *GetState;
    fmi2SetFMUstateTYPE *SetState;
    fmi2FreeFMUstateTYPE *FreeState;
    fmi2SerializedFMUstateSizeTYPE *StateSize;
    fmi2SerializeFMUstateTYPE *Serialize;
    fmi2DeSerializeFMUstateTYPE *Deserialize;
    fmi2GetDirectionalDerivativeTYPE *DirDer;
} api;

static int load(api *f, const char *lib) {
#ifdef LINKED
    (void)lib;
    f->Instantiate = fmi2Instantiate;
    f->FreeInstance = fmi2FreeInstance;
    f->SetupExperiment = fmi2SetupExperiment;
    f->EnterInit = fmi2EnterInitializationMode;
    f->ExitInit = fmi2ExitInitializationMode;
    f->Terminate = fmi2Terminate;
    f->Reset = fmi2Reset;
    f->SetReal = fmi2SetReal;
    f->GetReal = fmi2GetReal;
    f->DoStep = fmi2DoStep;
    f->GetState = fmi2GetFMUstate;
    f->SetState = fmi2SetFMUstate;
    f->FreeState = fmi2FreeFMUstate;
    f->StateSize = fmi2SerializedFMUstateSize;
    f->Serialize = fmi2SerializeFMUstate;
    f->Deserialize = fmi2DeSerializeFMUstate;
    f->DirDer = fmi2GetDirectionalDerivative;
    return 0;
#else
    void *h = dlopen(lib, RTLD_NOW | RTLD_LOCAL);
    if (h == NULL) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 1;
    }
#define SYM(field, name)                                          \
    if ((*(void **)&f->field = dlsym(h, name)) == NULL) {         \
        fprintf(stderr, "missing %s\n", name);                    \
        return 1;                                                 \
    }
    SYM(Instantiate, "fmi2Instantiate");
    SYM(FreeInstance, "fmi2FreeInstance");
    SYM(SetupExperiment, "fmi2SetupExperiment");
    SYM(EnterInit, "fmi2EnterInitializationMode");
    SYM(ExitInit, "fmi2ExitInitializationMode");
    SYM(Terminate, "fmi2Terminate");
    SYM(Reset, "fmi2Reset");
    SYM(SetReal, "fmi2SetReal");
    SYM(GetReal, "fmi2GetReal");
    SYM(DoStep, "fmi2DoStep");
    SYM(GetState, "fmi2GetFMUstate");
    SYM(SetState, "fmi2SetFMUstate");
    SYM(FreeState, "fmi2FreeFMUstate");
    SYM(StateSize, "fmi2SerializedFMUstateSize");
    SYM(Serialize, "fmi2SerializeFMUstate");
    SYM(Deserialize, "fmi2DeSerializeFMUstate");
    SYM(DirDer, "fmi2GetDirectionalDerivative");
    return 0;
#endif
}

static unsigned long messages;
static int quiet;
static char last_message[4096]; /* kept when quiet, for a failure's report */
static int last_status;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String fmt, ...) {
    (void)env, (void)category;
    char buf[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    messages++;
    memcpy(last_message, buf, sizeof buf);
    last_status = (int)status;
    if (!quiet) fprintf(stderr, "[%s %d] %s\n", name, (int)status, buf);
}

static fmi2Component start(const api *f, const char *guid, const char *ident,
                           const fmi2CallbackFunctions *cb, const spec *s) {
    const char *res = getenv("FMU_RESOURCES"); /* the resources folder's URI, if any */
    fmi2Component c = f->Instantiate(ident, fmi2CoSimulation, guid, res ? res : "", cb,
                                     fmi2False, fmi2True);
    if (c == NULL) return NULL;
    f->SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    f->EnterInit(c);
    if (s->n_par) f->SetReal(c, s->par, (size_t)s->n_par, s->par_val);
    f->ExitInit(c);
    return c;
}

static int run(const api *f, const char *guid, const char *ident, FILE *in) {
    spec s;
    if (read_spec(in, &s)) return 2;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = start(f, guid, ident, &cb, &s);
    if (c == NULL) return 3;
    char tok[64];
    double u[16], y[32];
    for (;;) {
        double t, h;
        if (fscanf(in, "%63s", tok) != 1) break;
        t = strtod(tok, NULL);
        if (fscanf(in, "%63s", tok) != 1) return 2;
        h = strtod(tok, NULL);
        for (int i = 0; i < s.n_in; i++) {
            if (fscanf(in, "%63s", tok) != 1) return 2;
            u[i] = strtod(tok, NULL);
        }
        if (f->SetReal(c, s.in, (size_t)s.n_in, u) != fmi2OK) return 3;
        fmi2Status st = f->DoStep(c, t, h, fmi2True);
        if (st != fmi2OK) {
            printf("status %d\n", (int)st);
            continue;
        }
        if (f->GetReal(c, s.out, (size_t)s.n_out, y) != fmi2OK) return 3;
        for (int i = 0; i < s.n_out; i++) printf(i ? " %a" : "%a", y[i]);
        printf("\n");
    }
    f->Terminate(c);
    f->FreeInstance(c);
    return 0;
}

/* ---- fuzz ------------------------------------------------------------------------- */
static double extreme(void) {
    static const double pool[] = {0.0, -0.0, 1e308, -1e308, 6e306, 1.2e308, 5e-324, -5e-324,
                                  1e-300, 1.0, -1.0, 1e3, 1000.0, 190.98593171027443, 0.3};
    switch (rnd() % 5) {
    case 0: return NAN;
    case 1: return (rnd() & 1) ? INFINITY : -INFINITY;
    case 2: return pool[rnd() % (sizeof pool / sizeof pool[0])];
    case 3: return (uniform() - 0.5) * pow(10.0, (double)(rnd() % 40) - 20.0);
    default: return (uniform() - 0.5) * 400.0; /* loads around mu P */
    }
}

/* A state call with a pointer that is not a live state of c (FMI 2.0 forbids it): a state
 * of c freed just before (set, freed twice, ...), a live state of another instance, one
 * of an instance freed since, or a pointer into a buffer. Each must answer fmi2Error and
 * leave the pointer given as it was: 1 if so. (A freed state of c is made anew each
 * time: the allocator may hand its memory to a later state of c.) */
static int hostile_state(const api *f, fmi2Component c, fmi2Component other,
                         fmi2FMUstate alien, fmi2FMUstate saved, const char *guid,
                         const char *ident, const fmi2CallbackFunctions *cb, const spec *s) {
    static unsigned char junk[4096];
    fmi2FMUstate p = NULL;
    switch (rnd() % 4) {
    case 0:
        if (f->GetState(c, &p) != fmi2OK) return 1; /* refused: nothing to test */
        {
            fmi2FMUstate q = p; /* its address kept */
            if (f->FreeState(c, &q) != fmi2OK || q != NULL) return 0;
        }
        break;
    case 1: p = other && alien ? alien : junk; break;
    case 2: {
        fmi2Component gone = start(f, guid, ident, cb, s);
        if (gone == NULL || f->GetState(gone, &p) != fmi2OK) p = junk + 8;
        if (gone) f->FreeInstance(gone); /* and its states */
        break;
    }
    default:
        for (size_t i = 0; i < sizeof junk; i++) junk[i] = (unsigned char)rnd();
        p = junk + 8 * (rnd() % (sizeof junk / 8 - 1));
    }
    fmi2FMUstate q = p;
    size_t size = 0;
    unsigned char bytes[64];
    fmi2Status st;
    switch (rnd() % 6) {
    case 0: st = f->SetState(c, p); break;
    case 1: st = f->FreeState(c, &q); break;
    case 2: st = f->StateSize(c, p, &size); break;
    case 3: st = f->Serialize(c, p, (fmi2Byte *)bytes, sizeof bytes); break;
    case 4: st = f->GetState(c, &q); break;
    default: { /* intact bytes of a live state into p */
        if (saved == NULL || f->StateSize(c, saved, &size) != fmi2OK) return 1;
        unsigned char *b = malloc(size);
        if (b == NULL || f->Serialize(c, saved, (fmi2Byte *)b, size) != fmi2OK) return 0;
        st = f->Deserialize(c, (const fmi2Byte *)b, size, &q);
        free(b);
    }
    }
    if (st == fmi2Error && q == p) return 1;
    fprintf(stderr, "a pointer that is no state of the instance answered %d\n", (int)st);
    return 0;
}

static int fuzz(const api *f, const char *guid, const char *ident, FILE *in, unsigned long long seed,
                long n) {
    spec s;
    if (read_spec(in, &s)) return 2;
    rng_state = seed * 0x9E3779B97F4A7C15ull + 1;
    quiet = 1;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = start(f, guid, ident, &cb, &s);
    if (c == NULL) return 3;
    fmi2Component other = start(f, guid, ident, &cb, &s); /* its state is foreign to c */
    fmi2FMUstate alien = NULL;
    if (other) f->GetState(other, &alien);
    long count[5] = {0}, refused = 0;
    double t = 0.0;
    fmi2FMUstate saved = NULL;
    /* every variable a random call may name: inputs, parameters, outputs, and one past */
    fmi2ValueReference all[96];
    int n_all = 0;
    for (int i = 0; i < s.n_in; i++) all[n_all++] = s.in[i];
    for (int i = 0; i < s.n_par; i++) all[n_all++] = s.par[i];
    for (int i = 0; i < s.n_out; i++) all[n_all++] = s.out[i];
    all[n_all++] = 100000u;
    for (long k = 0; k < n; k++) {
        fmi2Status st = fmi2OK;
        switch (rnd() % 10) {
        case 0: case 1: case 2: { /* a value, mostly an input, extreme or not */
            fmi2ValueReference vr = rnd() % 4 ? s.in[rnd() % (unsigned)s.n_in]
                                              : all[rnd() % (unsigned)n_all];
            double v = rnd() % 3 ? extreme() : 100.0 * uniform();
            st = f->SetReal(c, &vr, 1, &v);
            break;
        }
        case 3: case 4: case 5: { /* a step, mostly a good one */
            static const double hs[] = {1e-4, 1.75e-4, 0.0, -1e-4, 1e-300, 1e3, 1e-9, 2.0};
            double h = rnd() % 4 ? 1.75e-4 : (rnd() % 5 ? hs[rnd() % 8] : extreme());
            double at = rnd() % 10 ? t : extreme();
            st = f->DoStep(c, at, h, fmi2True);
            if (st == fmi2OK) {
                t = at + h;
                double y[32];
                if (f->GetReal(c, s.out, (size_t)s.n_out, y) != fmi2OK) return 3;
                for (int i = 0; i < s.n_out; i++)
                    if (!isfinite(y[i])) {
                        fprintf(stderr, "non-finite output served with fmi2OK\n");
                        return 3;
                    }
            }
            break;
        }
        case 6: /* get or set a state, or a state call with what is not a state of c */
            if (rnd() % 3 == 0) {
                if (!hostile_state(f, c, other, alien, saved, guid, ident, &cb, &s)) return 3;
                refused++;
                st = fmi2Error;
            } else if (saved == NULL || rnd() % 2) st = f->GetState(c, &saved);
            else st = f->SetState(c, saved);
            break;
        case 7: { /* serialize, damage, deserialize: refused; the intact bytes accepted */
            if (saved == NULL) break;
            size_t size = 0;
            if (f->StateSize(c, saved, &size) != fmi2OK || size == 0) return 3;
            unsigned char *b = malloc(size);
            if (b == NULL || f->Serialize(c, saved, (fmi2Byte *)b, size) != fmi2OK) return 3;
            fmi2FMUstate back = NULL;
            int damage = (int)(rnd() % 3);
            size_t len = size;
            if (damage == 1) b[rnd() % size] ^= (unsigned char)(1u + rnd() % 255u);
            if (damage == 2) len = rnd() % size;
            st = f->Deserialize(c, (const fmi2Byte *)b, len, &back);
            if ((damage == 0) != (st == fmi2OK)) {
                fprintf(stderr, "deserialize: damage %d answered %d\n", damage, (int)st);
                return 3;
            }
            if (back != NULL) {
                if (rnd() % 2) f->SetState(c, back);
                f->FreeState(c, &back);
            }
            free(b);
            break;
        }
        case 8: { /* the directional derivative (or, where not provided, an error, no
                   * harm) of an output along an input, both taken in turn by the call's
                   * index (no draw: the random sequence of the other calls is kept) */
            fmi2ValueReference u = s.in[k % s.n_in], z = s.out[(k / 7) % s.n_out];
            double dv = 1.0, dz = 0.0;
            st = f->DirDer(c, &u, 1, &z, 1, &dv, &dz);
            if (st == fmi2OK && !isfinite(dz)) {
                fprintf(stderr, "non-finite derivative served with fmi2OK\n");
                return 3;
            }
            break;
        }
        default: /* now and then start over */
            if (rnd() % 20 == 0) {
                st = f->Reset(c);
                f->SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
                f->EnterInit(c);
                f->SetReal(c, s.par, (size_t)s.n_par, s.par_val);
                f->ExitInit(c);
                t = 0.0;
            }
        }
        if ((int)st < 0 || (int)st >= 5 || st == fmi2Fatal) {
            fprintf(stderr, "status %d\n", (int)st);
            return 3;
        }
        count[st]++;
    }
    if (saved) f->FreeState(c, &saved);
    f->Terminate(c);
    f->FreeInstance(c);
    if (other) f->FreeInstance(other); /* alien with it */
    printf("ok %ld warning %ld discard %ld error %ld messages %lu refused %ld\n", count[0],
           count[1], count[2], count[3], messages, refused);
    return 0;
}

/* ---- many states ------------------------------------------------------------------ */
static double seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void shuffle(fmi2FMUstate *a, long n) {
    for (long i = n - 1; i > 0; i--) {
        long j = (long)(rnd() % (unsigned long long)(i + 1));
        fmi2FMUstate x = a[i];
        a[i] = a[j], a[j] = x;
    }
}

static int states(const api *f, const char *guid, const char *ident, FILE *in, long n) {
    spec s;
    if (read_spec(in, &s) || n < 1) return 2;
    rng_state = 0x9E3779B97F4A7C15ull;
    quiet = 1;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = start(f, guid, ident, &cb, &s);
    fmi2FMUstate *held = calloc((size_t)n, sizeof *held);
    if (c == NULL || held == NULL) return 3;
    double t0 = seconds();
    for (long i = 0; i < n; i++)
        if (f->GetState(c, &held[i]) != fmi2OK) return 3;
    double t1 = seconds();
    shuffle(held, n);
    for (long i = 0; i < n; i++)
        if (f->SetState(c, held[i]) != fmi2OK) return 3;
    double t2 = seconds();
    shuffle(held, n);
    size_t size = 0;
    for (long i = 0; i < n; i++) /* the lookup alone: no state's memory is touched */
        if (f->StateSize(c, held[i], &size) != fmi2OK) return 3;
    double t2b = seconds();
    for (long i = 0; i < n; i++) {
        fmi2FMUstate q = held[i];
        if (f->FreeState(c, &q) != fmi2OK || q != NULL) return 3;
    }
    double t3 = seconds();
    /* every freed one refused; then n anew, half freed: the others still set (the
     * set's deletions keep every live state findable) */
    for (long i = 0; i < n; i++)
        if (f->SetState(c, held[i]) != fmi2Error) return 3;
    for (long i = 0; i < n; i++) {
        held[i] = NULL;
        if (f->GetState(c, &held[i]) != fmi2OK) return 3;
    }
    for (long i = 0; i < n; i += 2) {
        fmi2FMUstate q = held[i];
        if (f->FreeState(c, &q) != fmi2OK) return 3;
    }
    for (long i = 0; i < n; i++)
        if (f->SetState(c, held[i]) != (i % 2 ? fmi2OK : fmi2Error)) return 3;
    f->FreeInstance(c); /* with the odd ones */
    free(held);
    printf("get_ns %.1f set_ns %.1f size_ns %.1f free_ns %.1f\n", 1e9 * (t1 - t0) / (double)n,
           1e9 * (t2 - t1) / (double)n, 1e9 * (t2b - t2) / (double)n,
           1e9 * (t3 - t2b) / (double)n);
    return 0;
}

/* ---- bench ------------------------------------------------------------------------ */
static int bench_failed(const char *call, long k, double t, fmi2Status st) {
    fprintf(stderr, "bench: %s at step %ld (t = %.17g s) answered %d; the FMU's last message "
            "(status %d): %s\n", call, k, t, (int)st, last_status,
            last_message[0] ? last_message : "(none)");
    return 3;
}
static int bench(const api *f, const char *guid, const char *ident, FILE *in, long n) {
    spec s;
    if (read_spec(in, &s) || n <= 0) return 2;
    /* the case: its rows "t h u_1 ... u_n", run in turn from its start state again and
     * again (a master repeating a scene), so that any N steps stay within the case */
    const size_t width = 2 + (size_t)s.n_in;
    size_t rows;
    double *tab = read_rows(in, s.n_in, &rows);
    if (tab == NULL) {
        fprintf(stderr, "bench: SPEC has no rows of \"t h u...\" (or no memory)\n");
        return 2;
    }
    quiet = 1;
    fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
    fmi2Component c = start(f, guid, ident, &cb, &s);
    if (c == NULL) return bench_failed("fmi2Instantiate", 0, 0.0, fmi2Error);
    fmi2FMUstate start_state = NULL;
    fmi2Status st = f->GetState(c, &start_state);
    if (st != fmi2OK) return bench_failed("fmi2GetFMUstate", 0, 0.0, st);
    /* the outputs at the end of the case: every repeat must end with the same doubles
     * (the start state set back is the start), else the run measured something else */
    double y[32] = {0}, end[32], best = INFINITY;
    int have_end = 0;
    for (int rep = 0; rep < 3; rep++) {
        struct timespec a, b;
        size_t r = 0;
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (long k = 0; k < n; k++) {
            const double *row = tab + r * width;
            if (r == 0 && (st = f->SetState(c, start_state)) != fmi2OK)
                return bench_failed("fmi2SetFMUstate", k, row[0], st);
            if ((st = f->SetReal(c, s.in, (size_t)s.n_in, row + 2)) != fmi2OK)
                return bench_failed("fmi2SetReal", k, row[0], st);
            if ((st = f->DoStep(c, row[0], row[1], fmi2True)) != fmi2OK)
                return bench_failed("fmi2DoStep", k, row[0], st);
            if ((st = f->GetReal(c, s.out, (size_t)s.n_out, y)) != fmi2OK)
                return bench_failed("fmi2GetReal", k, row[0], st);
            if (++r == rows) { /* the end of the case: once per repeat, not timed apart */
                r = 0;
                if (!have_end) memcpy(end, y, sizeof y), have_end = 1;
                else if (memcmp(end, y, (size_t)s.n_out * sizeof y[0]) != 0) {
                    fprintf(stderr, "bench: the case repeated from its start state ended with "
                            "other outputs at step %ld\n", k);
                    return 3;
                }
            }
        }
        clock_gettime(CLOCK_MONOTONIC, &b);
        double dt = (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec);
        best = dt < best ? dt : best;
    }
    for (int i = 0; i < s.n_out; i++)
        if (!isfinite(y[i])) {
            fprintf(stderr, "bench: a non-finite output served with fmi2OK\n");
            return 3;
        }
    printf("%.6g\n", (double)n / best);
    f->FreeState(c, &start_state);
    f->Terminate(c);
    f->FreeInstance(c);
    free(tab);
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: %s LIB GUID IDENT run|fuzz|bench SPEC [SEED N | N]\n", argv[0]);
        return 2;
    }
    api f;
    if (load(&f, argv[1])) return 2;
    FILE *in = fopen(argv[5], "r");
    if (in == NULL) return 2;
    int rc;
    if (strcmp(argv[4], "run") == 0) rc = run(&f, argv[2], argv[3], in);
    else if (strcmp(argv[4], "bench") == 0 && argc >= 7)
        rc = bench(&f, argv[2], argv[3], in, strtol(argv[6], NULL, 10));
    else if (strcmp(argv[4], "states") == 0 && argc >= 7)
        rc = states(&f, argv[2], argv[3], in, strtol(argv[6], NULL, 10));
    else if (strcmp(argv[4], "fuzz") == 0 && argc >= 8)
        rc = fuzz(&f, argv[2], argv[3], in, strtoull(argv[6], NULL, 10), strtol(argv[7], NULL, 10));
    else rc = 2;
    fclose(in);
    return rc;
}
