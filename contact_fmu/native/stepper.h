/* The compiled kernel's interface (stepper.c): its types and the functions other
 * files call (the structs it shares with Python, the order of a body step's outputs and
 * the Python numerics' constants are cf_abi.h's, generated from contact_fmu/native/abi.py). Two users: the ctypes library of contact_fmu/native/__init__.py (stepper.c
 * alone, built with CF_KERNEL_EXPORT so that ctypes finds cf_advance, cf_body_step,
 * cf_body_outputs, cf_strip_march, cf_layer_forces, cf_advance_vector) and the native
 * FMU (model.c, instance.c on stepper.c), whose library exports the fmi2 functions only:
 * every function declared here is CF_HIDDEN there, by the sources themselves, so that a
 * build without -fvisibility=hidden (fmpy's cmake, an importer's own) exports nothing
 * else. Also the settings every file of the numerics shares: no contraction into fused
 * multiply-adds, M_PI, the C library's oldest symbol versions (CF_GLIBC_COMPAT). */
#ifndef CF_STEPPER_H
#define CF_STEPPER_H

#include <math.h>
#include <stddef.h>

#include "cf_abi.h" /* the structs and constants shared with Python (generated) */
#include "cf_core.h"

/* Internal linkage across the files of one library: hidden from its dynamic symbol
 * table (GCC, Clang; elsewhere nothing is exported without a declaration saying so),
 * visible in the ctypes kernel (CF_KERNEL_EXPORT). */
#if defined(CF_KERNEL_EXPORT) || !(defined(__GNUC__) || defined(__clang__))
#define CF_HIDDEN
#else
#define CF_HIDDEN __attribute__((visibility("hidden")))
#endif
/* The Python path's roundings wherever this file is compiled (the native FMU's
 * sources/ too, by a build this project does not control): no contraction into fused
 * multiply-adds (gcc takes -ffp-contract=off from its flags; clang and MSVC this). */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#endif
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The C library's oldest versions of the symbols whose default version is newer than
 * the floor of manylinux2014 (glibc 2.17): hypot (2.35), pow and log (2.29) and fmod
 * (2.38) were re-versioned when their errno handling changed, not their values (the
 * compat entries wrap the same __ieee754_hypot, __pow, __log, __ieee754_fmod), so the
 * binaries built here (with CF_GLIBC_COMPAT, linked with -lm) load on RHEL/Rocky 8-9
 * and older (tests/test_native.py reads the versions they need). A build elsewhere (a
 * source FMU) binds its own C library's defaults. */
#if defined(CF_GLIBC_COMPAT) && defined(__GLIBC__) && defined(__x86_64__)
__asm__(".symver hypot,hypot@GLIBC_2.2.5");
__asm__(".symver pow,pow@GLIBC_2.2.5");
__asm__(".symver log,log@GLIBC_2.2.5");
__asm__(".symver fmod,fmod@GLIBC_2.2.5");
#elif defined(CF_GLIBC_COMPAT) && defined(__GLIBC__) && defined(__aarch64__)
__asm__(".symver hypot,hypot@GLIBC_2.17");
__asm__(".symver pow,pow@GLIBC_2.17");
__asm__(".symver log,log@GLIBC_2.17");
__asm__(".symver fmod,fmod@GLIBC_2.17");
#endif

#define CF_OK 0
#define CF_FALLBACK 1

/* cf_params.law */
enum { LAW_LAYER = 0, LAW_TABLE = 1 };
/* the most load nodes of a creep-force table (cf_params.n_loads; the build refuses more) */
#define CF_LOADS_MAX 16

/* ---- fmu/body_model.py: a communication step of the body (cf_body) ---------------- */
/* Why a communication step of the body is not served (else CF_OK): the checks of
 * BodyModel.step and the adapter, once for both front ends. fmi.c's fast path takes
 * any of them as CF_FALLBACK (cf_body_step: the Python adapter then words the refusal),
 * the native FMU's doStep (instance.c) words each as the adapter does. */
enum {
    CF_STEP_LAW = 2,   /* the law is not at the load P (Python rebuilds it: Eq. 34) */
    CF_STEP_SIZE,      /* h not in (0, inf), or no h_max > 0 */
    CF_STEP_FX_LIMIT,  /* |Fx_ex| beyond integrator.LOAD_LIMIT mu P (or NaN) */
    CF_STEP_MY_LIMIT,  /* |My_ex| beyond LOAD_LIMIT mu P Rx (or NaN) */
    CF_STEP_CAPPED,    /* more internal steps than max_substeps (n is that cap) */
    CF_STEP_NO_SLIDING, /* loads beyond mu P on an eta = inf body (Iy = 0), full method */
    CF_STEP_NO_ROOT,   /* the stepper declined: no stage root, a non-finite state */
    CF_STEP_RANGE,     /* a speed or rate beyond its range: ranges.within_range */
    CF_STEP_NONFINITE, /* an output served is not finite: slave._collect */
};

/* ranges.within_range's table: the output, its name, its bound */
typedef struct {
    int i;
    const char *name;
    double bound;
} cf_ranged;
static const cf_ranged CF_RANGED[4] = {
    {O_VX, "Vx", CF_SPEED_MAX},
    {O_VY, "Vy", CF_SPEED_MAX},
    {O_OMEGA_Y, "Omega_y", CF_RATE_MAX},
    {O_OMEGA_Z, "Omega_z", CF_RATE_MAX},
};

/* The vector path of a step (Eqs. 10-11: the native FMU's CF_VECTOR): its state, the lateral
 * loads, the spin grid's scratch and mask (cf_vbody_outputs) */
typedef struct {
    cf_vstate *y;
    double Fy_ex, Mz_ex;
    double *tau;
    unsigned char *slip;
    const unsigned char *inside;
} cf_vpath;

#define CF_ALL_OUT ((1ul << N_OUT) - 1ul)

/* ---- the functions (stepper.c, where each is described) ---------------------------- */
/* the steps: ctypes (Kernel, VectorKernel) and the native FMU */
CF_HIDDEN int cf_advance(const cf_params *p, cf_state *y, double h, double Fx, double My, int n);
CF_HIDDEN int cf_advance_vector(const cf_params *p, cf_vstate *y, double h, const double *L,
                                int n);
/* the law's derived constants, the body's inertia, the initial forces, the outputs */
CF_HIDDEN void cf_layer_law(cf_params *p, double P, double Rx, double Ry, double k1, double k2,
                            double kb, double ks, double mu, double *a2, double *p0);
CF_HIDDEN void cf_table_law(cf_params *p, double P, double mu, double kfac, double m,
                            double Amin, int a_le_b, double Estar, double G, double onset,
                            double *a2, double *p0);
CF_HIDDEN void cf_body_inertia(cf_params *p, double M, double Rx, double Iy);
CF_HIDDEN void cf_initial_forces(const cf_params *p, cf_state *y);
CF_HIDDEN void cf_body_outputs(const cf_params *p, const cf_state *y, cf_body *b);
CF_HIDDEN void cf_initial_vforces(const cf_params *p, cf_vstate *y);
CF_HIDDEN void cf_vbody_outputs(const cf_params *p, const cf_vstate *y, cf_body *b, double *tau,
                                unsigned char *slip, const unsigned char *inside);
/* a communication step's checks, and the step (fmi.c's fast path through ctypes) */
CF_HIDDEN double cf_load_cap(const cf_params *p);
CF_HIDDEN int cf_body_admit(const cf_params *p, const cf_body *b, double h, int *n);
CF_HIDDEN int cf_first_nonfinite(const double *out, unsigned long served);
CF_HIDDEN int cf_body_out_check(const double *out, unsigned long served, int *which);
CF_HIDDEN int cf_body_check(const cf_params *p, cf_state *y, const cf_vpath *v, cf_body *b,
                            double h, int *capped, unsigned long served, int *which);
CF_HIDDEN int cf_body_step(const cf_params *p, cf_state *y, cf_body *b, double h);
/* the strip march of the spin law: its grid, forces, standstill, adhesion, derivative */
CF_HIDDEN int cf_strip_march(const cf_strips *g, int n, const double *vx, const double *vy,
                             const double *Vx, const double *phi, double *tau,
                             unsigned char *slip);
CF_HIDDEN int cf_layer_forces(const cf_params *p, const cf_strips *g, int n, const double *vx,
                              const double *vy, const double *phi, const double *Vx, double *T);
CF_HIDDEN void cf_march_standstill(const cf_strips *g, double vx, double vy, double phi,
                                   double R[3]);
CF_HIDDEN void cf_march_jacobian(const cf_strips *g, double vx, double vy, double Vx, double phi,
                                 double D[12]);
CF_HIDDEN void cf_grid_build(cf_strips *g, double *x, double *y, double *dist, double *mid,
                             double *cap, double *w, unsigned char *inside, int nx, int ny,
                             double a1, double a2, double p0, double mu, double k, double tiny);
CF_HIDDEN double cf_spin_adhesion(const cf_strips *g, double vx, double vy, double Vx,
                                  double phi, double *tau, unsigned char *slip,
                                  const unsigned char *inside);
/* the scalar law for the native FMU's contact mode and its derivatives (model.c) */
CF_HIDDEN void cf_law_forces(const cf_params *p, double vx, double vy, double Vx, double T[3]);
CF_HIDDEN void cf_table_forces(const cf_params *p, double vx, double vy, double phi, double Vx,
                               double out[4]);
CF_HIDDEN double cf_adhesion_fraction(const cf_params *p, double vx, double vy, double Vx);
CF_HIDDEN int cf_full_slip(const cf_params *p, double vx, double vy, double Vx);
CF_HIDDEN double cf_target_x(const cf_params *p, double Fx, double My);
CF_HIDDEN double cf_force_fraction(const cf_params *p, double beta);
CF_HIDDEN double cf_force_fraction_slope(const cf_params *p, double beta);

#endif
