/* The native FMU's model, shared by the instance layer (instance.c) and the model's
 * numerics (model.c): the variables of the generated cf_model.h (from
 * contact_fmu/fmu/variables.py) by role, the instance's core (everything an FMU state
 * holds) and the spin grid, and the model functions model.c defines. Not an interface
 * of the FMU: neither fmi2.c nor an FMI 3.0 front end includes it (they see instance.h).
 * Every function here is CF_HIDDEN: the library exports the fmi2* functions only. */
#ifndef CF_MODEL_H_INTERNAL
#define CF_MODEL_H_INTERNAL

#include "field.h"
#include "stepper.h"

/* ---- the variables (cf_model.h, generated from variables.py) ---------------------- */
enum { K_PARAMETER, K_INPUT, K_OUTPUT };
enum { T_REAL, T_INTEGER, T_STRING };

/* the parameters and inputs the model reads, by role */
enum {
    R_MU, R_RX, R_RY, R_K1, R_K2, R_KB, R_KS, R_M, R_IY, R_VY_RATIO, R_VX0, R_SLIP0,
    R_H_MAX, R_METHOD, R_P, R_FX_EX, R_MY_EX,
    R_VX, R_VY, R_OMEGA_Y, R_OMEGA_Z, R_TX, /* contact-mode kinematics, rigid_body's Tx */
    R_IZ, R_VY0, R_OMEGA_Z0, R_SPIN_RATIO, R_FY_EX, R_MZ_EX, /* Eqs. (10)-(11) */
    R_SCHEME, /* the integrator's scheme (a String, as R_METHOD) */
    R_MAX_WORK, /* the budget of one doStep (work units) */
    R_NX, R_NY, R_CELLS_PER_STEP, /* phase "transient": the field's grid and step */
    R_FIELD_FILE, R_FIELD_TIMES,  /* ... and its CSV file (Strings, as R_METHOD) */
    R_COUNT
};
/* the modes (CF_MODE): fmu/body_model.py, contact_model.py, rigid_body.py */
enum { MODE_BODY, MODE_CONTACT, MODE_RIGID };
#define R_OUT 1000 /* outputs: R_OUT + the index in cf_body.out, or in out_field: */
/* phase "transient": the field's summary outputs after cf_body.out's (TransientRollingBody
 * .outputs(): LayerField.summary), held in cf_tstate.fo */
enum { O_SLIP_CX = N_OUT, O_SLIP_CY, O_TAU_PEAK, N_OUT_ALL };

typedef struct {
    const char *name;
    int kind, type, role;
    double start;
    double lo, hi;             /* declared range (-inf, inf where none) */
    int open_lo;               /* lo itself excluded */
    const char *lo_req, *hi_req; /* Var.check's requirement texts: "> 0", "<= 1" */
    double fix;                  /* a value the build fixes (ModelConfig.fixed) ... */
    const char *fix_req;         /* ... and the requirement text, or NULL */
} cf_var;

#include "cf_model.h"

#define METHOD_TEXT 64

/* ---- phase "transient": the body on the thin-layer traction field (field.c) ---------- */
/* The grid is the scene's (CF_FIELD_NX cells along 2 a1, CF_FIELD_NY strips across 2 a2:
 * cf_model.h, 1 x 1 without the phase), compiled into the core so that an FMU state is
 * plain data; nx and ny are fixed to it (CF_VARS' fix). */
#define FIELD_N (CF_FIELD_NX * CF_FIELD_NY)
typedef struct {
    double y[4];                  /* TransientRollingBody.y: (Vx, vx, Vy, Omega_z) */
    double t, impulse[3];         /* its t and impulse */
    double T[3];                  /* out: (Tx, Ty, Mz) of the last step */
    int sliding;                  /* out.sliding */
    /* the field (LayerField): the lattice laid at the set-up load (dx, X), the strips
     * (ys, dy over Y = a2 there; sine rule), its state */
    double dx, X, Y;
    double ys[CF_FIELD_NY], dy[CF_FIELD_NY];
    double theta, direction;
    double tau_x[FIELD_N], tau_y[FIELD_N]; /* Pa, ny x nx row major */
    unsigned char slip[FIELD_N];
    double fo[N_OUT_ALL - N_OUT]; /* the summary outputs O_SLIP_CX ... */
} cf_tstate;

/* The field file (body_transient.FieldRecorder): field_file and field_times as set (a
 * longer text is refused), at most CF_FIELD_CAPTURES times, and a capture of the field at
 * each time reached (the law's a1, a2, p0, mu, P with it: the file is written from them
 * whole at each capture and after a restore of an FMU state with other captures) */
#define FIELD_TEXT (CF_TRANSIENT ? 1024 : 8)
#define CF_FIELD_CAPTURES 8
typedef struct {
    double wanted, t;             /* the requested time and the step's end (s) */
    double theta, direction;
    double a1, a2, p0, mu, P;     /* the law then */
    double tau_x[FIELD_N], tau_y[FIELD_N];
    unsigned char slip[FIELD_N];
} cf_capture;

/* ---- the instance's core ------------------------------------------------------------ */
enum { PH_INSTANTIATED, PH_INIT, PH_STEP, PH_TERMINATED };

/* Everything an FMU state holds: plain data, no pointer that is not NULL. */
typedef struct {
    double val[R_COUNT];          /* parameters and inputs by role */
    double var[CF_N_VARS];        /* every Real/Integer variable's value, by vr */
    unsigned bad[CF_N_VARS];      /* 0, or the order in which the value became bad */
    unsigned next_bad;
    int method;                   /* index into METHOD_NAMES, -1: not a method */
    char method_text[METHOD_TEXT]; /* the string set (cut at METHOD_TEXT - 1) */
    int scheme;                   /* index into SCHEME_NAMES, -1: not a scheme */
    char scheme_text[METHOD_TEXT]; /* the string set, as method_text */
    double time;
    int phase, built;
    int init_tried;               /* fmi2ExitInitializationMode was called */
    int dirty;                    /* contact mode: inputs set since the outputs */
    double rb_Vx, rb_Omega_y;     /* rigid_body mode's state */
    cf_vstate vs;                 /* body mode with Vy and/or Omega_z as unknowns */
    double P_law;                 /* the load the law's constants are for */
    cf_params p;
    cf_state s;
    cf_body b;
    cf_tstate fs;                 /* phase "transient" (1 x 1 without it) */
    char field_text[2][FIELD_TEXT]; /* field_file, field_times as set */
    int n_captured;               /* captures of the field file taken ... */
    cf_capture cap[CF_TRANSIENT ? CF_FIELD_CAPTURES : 1]; /* ... in cap[0 ... n_captured) */
} cf_core;

/* the spin grid of the vector path and of the contact mode's spin input (layer._Grid of
 * SPIN_GRID): a function of the law at its load (a1, a2, p0, mu, kb + ks), rebuilt when
 * one of them changes (a new load, a tuned mu, a reset), not part of the FMU state */
#define GRID_N (CF_SPIN_NX * CF_SPIN_NY)
#define CF_GRID ((CF_VECTOR || CF_CONTACT_SPIN) && !CF_TABLE)
typedef struct {
    double key[5];                /* the law it is for: a1, a2, p0, mu, k (NaN: none yet) */
    cf_strips strips;
    double x[CF_SPIN_NX], y[CF_SPIN_NY], dist[GRID_N], mid[GRID_N], cap[GRID_N], w[GRID_N];
    unsigned char inside[GRID_N];
    double tau[2 * GRID_N];       /* scratch of the adhesion's march */
    unsigned char slip[GRID_N];
} spin_grid;

/* the traction along the contact's centre line y = 0 (the FMI 3.0 FMU's arrays x_centre,
 * tau_x_centre, tau_y_centre): CF_LINE_N cells, on the thin-layer law in body and contact
 * mode (model_description3.has_line; CF_LINE_N, its LINE_N, comes with cf_model.h) */
#define CF_LINE (CF_MODE != MODE_RIGID && !CF_TABLE && !CF_TRANSIENT)

/* the scratch of the transient field's step (not state): the trial state, the field's
 * geometry at the law's load, cf_field_advance's work */
typedef struct {
    cf_tstate trial;
    double ell[CF_FIELD_NY], p_strip[CF_FIELD_NY], dy_w[CF_FIELD_NY];
    double work[CF_FIELD_ADVANCE_WORK(CF_FIELD_NY, CF_FIELD_NX)];
    unsigned char bytes[CF_FIELD_ADVANCE_BYTES(CF_FIELD_NY, CF_FIELD_NX)];
} field_scratch;

/* ---- the model's numerics (model.c) -------------------------------------------------- */
/* the Python integrator's constants into p and b (cf_abi.h) */
CF_HIDDEN void cf_model_constants(cf_params *p, cf_body *b);
/* the creep-force table's arrays (table: axes then patch coefficients) into p */
CF_HIDDEN void cf_model_attach_table(const double *table, cf_params *p);
/* the law at load P into p and b (its reported a2, p0) */
CF_HIDDEN void cf_model_law_at_load(const cf_core *c, double P, cf_params *p, cf_body *b);
/* the spin grid g for the law at its load, built unless it is already for it */
CF_HIDDEN const cf_strips *cf_model_grid(spin_grid *g, const cf_core *c, const cf_params *law,
                                         const cf_body *b);
/* the contact mode's outputs at c's inputs into out; -1, or the index into out of the
 * first output served (a bit per index) that is not finite */
CF_HIDDEN int cf_model_contact_outputs(const cf_core *c, spin_grid *g, cf_params *p, cf_body *b,
                                       double out[N_OUT], unsigned long served);
/* the rigid body's step of h under the held inputs into out (Vx, Omega_y; others 0) */
CF_HIDDEN void cf_model_rigid_step(const cf_core *c, double h, double out[N_OUT]);
/* d(Tx, Ty, Mz)/d(vx, vy, V, phi) at c's inputs, analytic; 0 where there is none */
CF_HIDDEN int cf_model_contact_jacobian(const cf_core *c, spin_grid *g, int need_phi,
                                        double J[3][4]);
/* layer.LayerContact.traction(vx, vy, Vx, nx = CF_LINE_N, ny = 1, phi) of the law at its
 * load (law, b): the cells' x (m), ascending, and tau_x, tau_y (Pa) there; all 0 without
 * contact (P = 0); 0 if the field is finite, else -1 (a non-finite input) */
CF_HIDDEN int cf_model_centre_line(const cf_core *c, const cf_params *law, const cf_body *b,
                                   double vx, double vy, double Vx, double phi,
                                   double line[3][CF_LINE_N]);
/* an output's row of d(outputs)/d(Vx, Vy, Omega_y, Omega_z) where analytic, else 0 */
CF_HIDDEN int cf_model_analytic_row(const cf_core *c, int role, int have, double J[3][4],
                                    double row[4]);

/* ---- phase "transient" (model.c) ------------------------------------------------------ */
/* LayerField.__init__ at the law's load (law, lb: a1, a2): the lattice (dx = 2 a1/nx, X =
 * a1), the strips (the sine rule over Y = a2), the field at rest (theta 0.5, tau 0) */
CF_HIDDEN void cf_model_field_lay(const cf_params *law, const cf_body *lb, cf_tstate *fs);
/* The field's geometry at the law's load (LayerField._update_contact: l(y), p at x = 0,
 * the scaled strip widths) into sc, the struct f (k = kb + ks) pointing there and into
 * fs's strips */
CF_HIDDEN void cf_model_field(const cf_params *law, const cf_body *lb, double k,
                              const cf_tstate *fs, field_scratch *sc, cf_field *f);
/* field_times parsed (body_transient.parse_times: numbers separated by spaces, commas or
 * semicolons, sorted) into times; their count, or -1 not numbers, -2 not finite, -3 more
 * than CF_FIELD_CAPTURES */
CF_HIDDEN int cf_model_field_times(const char *text, double times[CF_FIELD_CAPTURES]);
/* FieldRecorder.write: the captures cap[0 ... n) as the CSV file path (its folders made);
 * k = kb + ks; fs: the lattice and strips; 0, or -1 with errno's text in why */
CF_HIDDEN int cf_model_field_write(const char *path, const cf_capture *cap, int n, double k,
                                   const cf_tstate *fs, field_scratch *sc, char *why,
                                   size_t why_size);
/* TransientRollingBody.outputs() into out (N_OUT_ALL: cf_body.out's then the summary's)
 * and fs->fo; CF_FIELD_OK or field.c's refusal of the summary */
CF_HIDDEN int cf_model_field_outputs(const cf_params *law, const cf_body *lb, const cf_field *f,
                                     cf_tstate *fs, field_scratch *sc, double out[N_OUT_ALL]);

#endif
