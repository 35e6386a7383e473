/* A plain C FMI 3.0 co-simulation importer for the FMI 3.0 native FMU's tests (no Python).
 *
 *   native_importer3 LIB TOKEN run   SPEC        run a case: outputs of every step (hex)
 *   native_importer3 LIB TOKEN calls SPEC        the bad and unsupported calls: one line
 *                                              "call status" each (the FMI 3.0 status)
 *   native_importer3 LIB TOKEN bench SPEC N      N steps of the case, repeated from its
 *                                              start state: steps per second (the
 *                                              fastest of 3 passes)
 *   native_importer3 LIB TOKEN fuzz  SPEC SEED N TIME  N random calls with extreme
 *                                              values (TIME: the value reference of
 *                                              time, read after a state is set):
 *                                              counts of the statuses
 *
 * LIB is the FMU's shared library, opened with dlopen; built with -DLINKED (the sanitizer
 * build: the FMU's sources compiled into this program) the functions are called directly
 * and LIB is ignored. SPEC is native_importer.c's (line 1: the Float64 inputs' value
 * references "n vr...", line 2: the outputs', line 3: the parameters "n vr value...",
 * then for "run" one row per step "t h u_1 ... u_n", all values hex floats). "run" prints
 * each step's outputs and lastSuccessfulTime as hex floats, one line per step. Exit
 * status: 0 fine, 2 usage, 3 an FMI answer not allowed (fmi3Fatal, a non-finite output
 * served with fmi3OK, damaged bytes accepted, a step flag set). FMU_RESOURCES in the
 * environment: the resources folder (a path) to instantiate with.
 */
#include <math.h>
#include <time.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "importer_common.h"

#ifndef LINKED
#include <dlfcn.h>
#endif

typedef struct {
    fmi3InstantiateCoSimulationTYPE *Instantiate;
    fmi3InstantiateModelExchangeTYPE *InstantiateME;
    fmi3FreeInstanceTYPE *FreeInstance;
    fmi3EnterInitializationModeTYPE *EnterInit;
    fmi3ExitInitializationModeTYPE *ExitInit;
    fmi3TerminateTYPE *Terminate;
    fmi3ResetTYPE *Reset;
    fmi3SetFloat64TYPE *SetFloat64;
    fmi3GetFloat64TYPE *GetFloat64;
    fmi3GetInt32TYPE *GetInt32;
    fmi3GetFloat32TYPE *GetFloat32;
    fmi3DoStepTYPE *DoStep;
    fmi3GetFMUStateTYPE *GetState;
    fmi3SetFMUStateTYPE *SetState;
    fmi3FreeFMUStateTYPE *FreeState;
    fmi3SerializedFMUStateSizeTYPE *StateSize;
    fmi3SerializeFMUStateTYPE *Serialize;
    fmi3DeserializeFMUStateTYPE *Deserialize;
    fmi3GetDirectionalDerivativeTYPE *DirDer;
    fmi3GetAdjointDerivativeTYPE *AdjDer;
    fmi3EnterEventModeTYPE *EnterEventMode;
    fmi3EnterStepModeTYPE *EnterStepMode;
    fmi3EnterConfigurationModeTYPE *EnterConfig;
    fmi3UpdateDiscreteStatesTYPE *UpdateDiscrete;
    fmi3SetTimeTYPE *SetTime;
    fmi3GetClockTYPE *GetClock;
} api;

static int load(api *f, const char *lib) {
#ifdef LINKED
    (void)lib;
#define SYM(field, name) f->field = name;
#else
    void *h = dlopen(lib, RTLD_NOW | RTLD_LOCAL);
    if (h == NULL) {
        fprintf(stderr, "dlopen: %s\n", dlerror());
        return 1;
    }
#define SYM(field, name)                                          \
    if ((*(void **)&f->field = dlsym(h, #name)) == NULL) {        \
        fprintf(stderr, "missing %s\n", #name);                   \
        return 1;                                                 \
    }
#endif
    SYM(Instantiate, fmi3InstantiateCoSimulation)
    SYM(InstantiateME, fmi3InstantiateModelExchange)
    SYM(FreeInstance, fmi3FreeInstance)
    SYM(EnterInit, fmi3EnterInitializationMode)
    SYM(ExitInit, fmi3ExitInitializationMode)
    SYM(Terminate, fmi3Terminate)
    SYM(Reset, fmi3Reset)
    SYM(SetFloat64, fmi3SetFloat64)
    SYM(GetFloat64, fmi3GetFloat64)
    SYM(GetInt32, fmi3GetInt32)
    SYM(GetFloat32, fmi3GetFloat32)
    SYM(DoStep, fmi3DoStep)
    SYM(GetState, fmi3GetFMUState)
    SYM(SetState, fmi3SetFMUState)
    SYM(FreeState, fmi3FreeFMUState)
    SYM(StateSize, fmi3SerializedFMUStateSize)
    SYM(Serialize, fmi3SerializeFMUState)
    SYM(Deserialize, fmi3DeserializeFMUState)
    SYM(DirDer, fmi3GetDirectionalDerivative)
    SYM(AdjDer, fmi3GetAdjointDerivative)
    SYM(EnterEventMode, fmi3EnterEventMode)
    SYM(EnterStepMode, fmi3EnterStepMode)
    SYM(EnterConfig, fmi3EnterConfigurationMode)
    SYM(UpdateDiscrete, fmi3UpdateDiscreteStates)
    SYM(SetTime, fmi3SetTime)
    SYM(GetClock, fmi3GetClock)
    return 0;
}

static int quiet;
static unsigned long messages;

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message) {
    (void)env, (void)category;
    messages++;
    if (!quiet) fprintf(stderr, "[%d] %s\n", (int)status, message);
}

static fmi3Instance start(const api *f, const char *token, const spec *s) {
    const char *res = getenv("FMU_RESOURCES"); /* the resources folder, if any */
    fmi3Instance c = f->Instantiate("importer3", token, res, fmi3False, fmi3True, fmi3False,
                                    fmi3False, NULL, 0, NULL, log_message, NULL);
    if (c == NULL) return NULL;
    f->EnterInit(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    if (s->n_par) f->SetFloat64(c, s->par, (size_t)s->n_par, s->par_val, (size_t)s->n_par);
    if (f->ExitInit(c) != fmi3OK) {
        f->FreeInstance(c);
        return NULL;
    }
    return c;
}

/* one step; 3 where a flag FMI 3.0 adds is set (this FMU never sets one) */
static int step(const api *f, fmi3Instance c, double t, double h, fmi3Status *st, double *last) {
    fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
    *st = f->DoStep(c, t, h, fmi3True, &event, &terminate, &early, last);
    return event || terminate || early ? 3 : 0;
}

static int run(const api *f, const char *token, FILE *in) {
    spec s;
    if (read_spec(in, &s)) return 2;
    fmi3Instance c = start(f, token, &s);
    if (c == NULL) return 3;
    char tok[64];
    double u[16], y[32];
    for (;;) {
        double t, h, last = NAN;
        if (fscanf(in, "%63s", tok) != 1) break;
        t = strtod(tok, NULL);
        if (fscanf(in, "%63s", tok) != 1) return 2;
        h = strtod(tok, NULL);
        for (int i = 0; i < s.n_in; i++) {
            if (fscanf(in, "%63s", tok) != 1) return 2;
            u[i] = strtod(tok, NULL);
        }
        if (f->SetFloat64(c, s.in, (size_t)s.n_in, u, (size_t)s.n_in) != fmi3OK) return 3;
        fmi3Status st;
        if (step(f, c, t, h, &st, &last)) return 3;
        if (st != fmi3OK) {
            printf("status %d\n", (int)st);
            continue;
        }
        if (f->GetFloat64(c, s.out, (size_t)s.n_out, y, (size_t)s.n_out) != fmi3OK) return 3;
        for (int i = 0; i < s.n_out; i++) printf(i ? " %a" : "%a", y[i]);
        printf(" %a\n", last);
    }
    f->Terminate(c);
    f->FreeInstance(c);
    return 0;
}

/* ---- the bad and unsupported calls ---------------------------------------------------- */
#define SAY(name, expr) printf("%s %d\n", name, (int)(expr))

static int calls(const api *f, const char *token, FILE *in) {
    spec s;
    if (read_spec(in, &s) || s.n_in < 1) return 2;
    /* instantiation refused: another token, event mode, model exchange */
    SAY("token", f->Instantiate("x", "{not-this}", NULL, fmi3False, fmi3True, fmi3False,
                                fmi3False, NULL, 0, NULL, log_message, NULL) != NULL);
    SAY("eventMode", f->Instantiate("x", token, NULL, fmi3False, fmi3True, fmi3True,
                                    fmi3False, NULL, 0, NULL, log_message, NULL) != NULL);
    SAY("modelExchange", f->InstantiateME("x", token, NULL, fmi3False, fmi3True, NULL,
                                          log_message) != NULL);
    fmi3Instance c = start(f, token, &s);
    if (c == NULL) return 3;
    fmi3Status st;
    double u0[16], y[32], last = NAN, h = 1.75e-4;
    const fmi3ValueReference vr = s.in[0];
    if (f->GetFloat64(c, s.in, (size_t)s.n_in, u0, (size_t)s.n_in) != fmi3OK) return 3;
    if (step(f, c, 0.0, h, &st, &last)) return 3;
    SAY("doStep", st);
    const double nan = NAN;
    SAY("setNaN", f->SetFloat64(c, &vr, 1, &nan, 1));
    if (step(f, c, h, h, &st, &last)) return 3;
    SAY("doStepHeld", st);
    printf("lastSuccessfulTime %a\n", last);
    SAY("getHeld", f->GetFloat64(c, &vr, 1, y, 1));
    SAY("setGood", f->SetFloat64(c, &vr, 1, u0, 1));
    if (step(f, c, h, h, &st, &last)) return 3;
    SAY("doStepAgain", st);
    SAY("nValues", f->GetFloat64(c, s.out, (size_t)s.n_out, y, 1));
    /* FMU state: get, step, set back, step again: the same outputs */
    fmi3FMUState state = NULL;
    SAY("getState", f->GetState(c, &state));
    double a[32], b[32];
    if (step(f, c, 2 * h, h, &st, &last) || st != fmi3OK) return 3;
    f->GetFloat64(c, s.out, (size_t)s.n_out, a, (size_t)s.n_out);
    SAY("setState", f->SetState(c, state));
    if (step(f, c, 2 * h, h, &st, &last) || st != fmi3OK) return 3;
    f->GetFloat64(c, s.out, (size_t)s.n_out, b, (size_t)s.n_out);
    printf("repeated %d\n", memcmp(a, b, (size_t)s.n_out * sizeof a[0]) == 0);
    size_t size = 0;
    SAY("stateSize", f->StateSize(c, state, &size));
    fmi3Byte *bytes = (fmi3Byte *)malloc(size);
    if (bytes == NULL) return 3;
    SAY("serialize", f->Serialize(c, state, bytes, size));
    fmi3FMUState back = NULL;
    SAY("deserialize", f->Deserialize(c, bytes, size, &back));
    SAY("freeBack", f->FreeState(c, &back));
    bytes[size / 2] ^= 0x08;
    back = NULL;
    st = f->Deserialize(c, bytes, size, &back);
    SAY("flipped", st);
    if (st == fmi3OK) return 3;
    SAY("truncated", f->Deserialize(c, bytes, size - 1, &back));
    free(bytes);
    SAY("freeState", f->FreeState(c, &state));
    SAY("freeFreed", f->FreeState(c, &state)); /* NULL now: nothing to free */
    /* what this FMU does not provide */
    const fmi3ValueReference z = s.out[0];
    const double one = 1.0;
    double dz = 0.0;
    SAY("directional", f->DirDer(c, &z, 1, &vr, 1, &one, 1, &dz, 1));
    SAY("adjoint", f->AdjDer(c, &z, 1, &vr, 1, &one, 1, &dz, 1));
    float x32;
    SAY("getFloat32", f->GetFloat32(c, &vr, 1, &x32, 1));
    SAY("enterEventMode", f->EnterEventMode(c));
    SAY("enterStepMode", f->EnterStepMode(c));
    SAY("enterConfigurationMode", f->EnterConfig(c));
    fmi3Boolean b1, b2, b3, b4, b5;
    double next;
    SAY("updateDiscreteStates", f->UpdateDiscrete(c, &b1, &b2, &b3, &b4, &b5, &next));
    SAY("setTime", f->SetTime(c, 0.0));
    fmi3Clock clk;
    SAY("getClock", f->GetClock(c, &vr, 1, &clk));
    SAY("reset", f->Reset(c));
    SAY("enterInit", f->EnterInit(c, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    SAY("exitInit", f->ExitInit(c));
    if (step(f, c, 0.0, h, &st, &last)) return 3;
    SAY("doStepAfterReset", st);
    SAY("terminate", f->Terminate(c));
    f->FreeInstance(c);
    printf("messages %lu\n", messages);
    return 0;
}

/* ---- fuzz ---------------------------------------------------------------------------- */
static double extreme(void) {
    static const double v[] = {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 1e300, -1e300,
                               1.7976931348623157e308, 5e-324, INFINITY, -INFINITY, NAN};
    const unsigned k = (unsigned)(rnd() % 16);
    if (k < sizeof v / sizeof v[0]) return v[k];
    return ldexp(uniform() - 0.5, (int)(rnd() % 80) - 40);
}

static int fuzz(const api *f, const char *token, FILE *in, unsigned long long seed, long n,
                fmi3ValueReference time_vr) {
    spec s;
    if (read_spec(in, &s)) return 2;
    rng_state = seed * 2654435761ull + 88172645463325252ull;
    quiet = 1;
    fmi3Instance c = start(f, token, &s);
    if (c == NULL) return 3;
    long count[5] = {0, 0, 0, 0, 0};
    double t = 0.0, y[32];
    fmi3FMUState state = NULL;
    for (long k = 0; k < n; k++) {
        fmi3Status st = fmi3OK;
        const unsigned what = (unsigned)(rnd() % 8);
        if (what < 3) { /* an input or a parameter: extreme values */
            const int par = s.n_par && rnd() % 3 == 0;
            const fmi3ValueReference vr = par ? s.par[rnd() % (unsigned)s.n_par]
                                              : s.in[rnd() % (unsigned)s.n_in];
            const double x = extreme();
            st = f->SetFloat64(c, &vr, 1, &x, 1);
        } else if (what < 6) { /* a step: mostly good, sometimes not */
            double h = rnd() % 4 ? 1.75e-4 : extreme(), last = NAN;
            const double at = rnd() % 8 ? t : extreme();
            if (step(f, c, at, h, &st, &last)) return 3;
            if (st == fmi3OK) t = last;
            if (st == fmi3OK) {
                if (f->GetFloat64(c, s.out, (size_t)s.n_out, y, (size_t)s.n_out) == fmi3OK)
                    for (int i = 0; i < s.n_out; i++)
                        if (!isfinite(y[i])) {
                            fprintf(stderr, "non-finite output served with fmi3OK\n");
                            return 3;
                        }
            }
        } else if (what == 6) { /* states */
            if (state == NULL) st = f->GetState(c, &state);
            else if (rnd() % 2) st = f->SetState(c, state);
            else st = f->FreeState(c, &state);
            if (st == fmi3OK && f->GetFloat64(c, &time_vr, 1, &t, 1) != fmi3OK) return 3;
        } else { /* a reset now and then */
            if (rnd() % 16 == 0) {
                if (state) f->FreeState(c, &state);
                st = f->Reset(c);
                f->EnterInit(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
                if (s.n_par) f->SetFloat64(c, s.par, (size_t)s.n_par, s.par_val, (size_t)s.n_par);
                f->ExitInit(c);
                t = 0.0;
            }
        }
        if (st == fmi3Fatal) {
            fprintf(stderr, "fmi3Fatal at call %ld\n", k);
            return 3;
        }
        count[st]++;
    }
    if (state) f->FreeState(c, &state);
    f->Terminate(c);
    f->FreeInstance(c);
    printf("ok %ld warning %ld discard %ld error %ld\n", count[0], count[1], count[2], count[3]);
    return 0;
}

/* ---- bench: native_importer.c's, in FMI 3.0's calls ----------------------------------- */
static int bench_failed(const char *call, long k, double t, fmi3Status st) {
    fprintf(stderr, "bench: %s at step %ld (t = %.17g s) answered %d\n", call, k, t, (int)st);
    return 3;
}

static int bench(const api *f, const char *token, FILE *in, long n) {
    spec s;
    if (read_spec(in, &s) || n <= 0) return 2;
    /* the case's rows run in turn from its start state again and again (a master
     * repeating a scene), so that any N steps stay within the case */
    const size_t width = 2 + (size_t)s.n_in;
    size_t rows;
    double *tab = read_rows(in, s.n_in, &rows);
    if (tab == NULL) return 2;
    quiet = 1;
    fmi3Instance c = start(f, token, &s);
    if (c == NULL) return bench_failed("fmi3InstantiateCoSimulation", 0, 0.0, fmi3Error);
    fmi3FMUState start_state = NULL;
    fmi3Status st = f->GetState(c, &start_state);
    if (st != fmi3OK) return bench_failed("fmi3GetFMUState", 0, 0.0, st);
    /* every repeat must end with the outputs of the first (the start state set back) */
    double y[32] = {0}, end[32], best = INFINITY, last;
    int have_end = 0;
    for (int rep = 0; rep < 3; rep++) {
        struct timespec a, b;
        size_t r = 0;
        clock_gettime(CLOCK_MONOTONIC, &a);
        for (long k = 0; k < n; k++) {
            const double *row = tab + r * width;
            if (r == 0 && (st = f->SetState(c, start_state)) != fmi3OK)
                return bench_failed("fmi3SetFMUState", k, row[0], st);
            if ((st = f->SetFloat64(c, s.in, (size_t)s.n_in, row + 2, (size_t)s.n_in)) != fmi3OK)
                return bench_failed("fmi3SetFloat64", k, row[0], st);
            if (step(f, c, row[0], row[1], &st, &last) || st != fmi3OK)
                return bench_failed("fmi3DoStep", k, row[0], st);
            if ((st = f->GetFloat64(c, s.out, (size_t)s.n_out, y, (size_t)s.n_out)) != fmi3OK)
                return bench_failed("fmi3GetFloat64", k, row[0], st);
            if (++r == rows) {
                r = 0;
                if (!have_end) memcpy(end, y, sizeof y), have_end = 1;
                else if (memcmp(end, y, (size_t)s.n_out * sizeof y[0]) != 0) return 3;
            }
        }
        clock_gettime(CLOCK_MONOTONIC, &b);
        double dt = (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec);
        best = dt < best ? dt : best;
    }
    for (int i = 0; i < s.n_out; i++)
        if (!isfinite(y[i])) return 3;
    printf("%.6g\n", (double)n / best);
    f->FreeState(c, &start_state);
    f->Terminate(c);
    f->FreeInstance(c);
    free(tab);
    return 0;
}

int main(int argc, char **argv) {
    if (argc < 5) {
        fprintf(stderr, "usage: %s LIB TOKEN run|calls|bench|fuzz SPEC [N | SEED N TIME]\n",
                argv[0]);
        return 2;
    }
    api f;
    if (load(&f, argv[1])) return 2;
    FILE *in = fopen(argv[4], "r");
    if (in == NULL) return 2;
    int rc;
    if (strcmp(argv[3], "run") == 0) rc = run(&f, argv[2], in);
    else if (strcmp(argv[3], "calls") == 0) rc = calls(&f, argv[2], in);
    else if (strcmp(argv[3], "bench") == 0 && argc >= 6)
        rc = bench(&f, argv[2], in, strtol(argv[5], NULL, 10));
    else if (strcmp(argv[3], "fuzz") == 0 && argc >= 8)
        rc = fuzz(&f, argv[2], in, strtoull(argv[5], NULL, 10), strtol(argv[6], NULL, 10),
                  (fmi3ValueReference)strtoul(argv[7], NULL, 10));
    else rc = 2;
    fclose(in);
    return rc;
}
