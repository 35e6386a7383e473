/* What the two C importers of the tests share (native_importer.c: FMI 2.0,
 * native_importer3.c: FMI 3.0): the spec file they read and the random numbers of their
 * fuzz runs. The spec: line 1 the inputs' value references "n vr...", line 2 the
 * outputs', line 3 the parameters "n vr value..." (values hex floats). */
#ifndef IMPORTER_COMMON_H
#define IMPORTER_COMMON_H

#include <stdio.h>
#include <stdlib.h>

typedef unsigned int vref; /* fmi2ValueReference and fmi3ValueReference (uint32_t) */

typedef struct {
    int n_in, n_out, n_par;
    vref in[16], out[32], par[32];
    double par_val[32];
} spec;

static inline int read_list(FILE *f, int *n, vref *vr, int cap) {
    if (fscanf(f, "%d", n) != 1 || *n < 0 || *n > cap) return 1;
    for (int i = 0; i < *n; i++)
        if (fscanf(f, "%u", &vr[i]) != 1) return 1;
    return 0;
}

static inline int read_spec(FILE *f, spec *s) {
    if (read_list(f, &s->n_in, s->in, 16) || read_list(f, &s->n_out, s->out, 32)) return 1;
    if (fscanf(f, "%d", &s->n_par) != 1 || s->n_par < 0 || s->n_par > 32) return 1;
    for (int i = 0; i < s->n_par; i++) {
        char v[64];
        if (fscanf(f, "%u %63s", &s->par[i], v) != 2) return 1;
        s->par_val[i] = strtod(v, NULL);
    }
    return 0;
}

/* The rows "t h u_1 ... u_n_in" that follow the spec, to the end of the file: a table of
 * *rows x (2 + n_in) doubles (free it), or NULL (no row, a short row, no memory). */
static inline double *read_rows(FILE *in, int n_in, size_t *rows) {
    const size_t width = 2 + (size_t)n_in;
    size_t cap = 256;
    double *tab = (double *)malloc(cap * width * sizeof *tab);
    char tok[64];
    *rows = 0;
    while (tab != NULL && fscanf(in, "%63s", tok) == 1) {
        if (*rows == cap) {
            double *more = (double *)realloc(tab, 2 * cap * width * sizeof *tab);
            if (more == NULL) break;
            tab = more, cap *= 2;
        }
        double *row = tab + *rows * width;
        row[0] = strtod(tok, NULL);
        for (size_t i = 1; i < width; i++) {
            if (fscanf(in, "%63s", tok) != 1) {
                free(tab);
                return NULL;
            }
            row[i] = strtod(tok, NULL);
        }
        (*rows)++;
    }
    if (tab != NULL && (*rows == 0 || !feof(in))) {
        free(tab);
        return NULL;
    }
    return tab;
}

static unsigned long long rng_state; /* the fuzz run's seed, then its state */

static inline unsigned long long rnd(void) { /* xorshift64* */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ull;
}

static inline double uniform(void) { return (double)(rnd() >> 11) / 9007199254740992.0; }

#endif
