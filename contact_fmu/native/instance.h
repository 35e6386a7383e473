/* The native FMU's instance layer: one FMU instance, whatever version of FMI calls it.
 *
 * instance.c holds every rule of the FMU that is not FMI 2.0 plumbing: the phases
 * (instantiated, initialisation, stepping, terminated) and which call each admits, the
 * checks of a value against its declared range, of a step's time and size and the
 * admission of a step, every message (in the words of contact_fmu/fmu/messages.py, the
 * pythonfmu FMU's too: the generated cf_messages.h), the FMU states (one format, one registry of the live
 * states an instance handed out), their serialisation, the creep-force table resource
 * (a file URI) and its CRC. A front end (fmi2.c for FMI 2.0, fmi3.c for FMI 3.0)
 * translates its arguments and statuses and calls these functions, a few lines each.
 *
 * The functions mirror the FMI 2.0 co-simulation calls with version-neutral names and
 * types: value references are unsigned, Reals double, Integers int, Strings char
 * pointers; each answers a cf_status whose values are FMI 2.0's and FMI 3.0's (OK 0,
 * Warning 1, Discard 2, Error 3, Fatal 4). A refusal is logged before the call returns,
 * through the front end's logger; no function answers CF_FATAL. A NULL instance is the
 * front end's to refuse. Messages that name an FMI call or status begin the name with
 * the API prefix given at instantiation, "fmi2" or "fmi3", and name the call as that
 * version does ("fmi2SetReal: ..." / "fmi3SetFloat64: ...", "fmi2DeSerializeFMUstate" /
 * "fmi3DeserializeFMUState", "doStep answers fmi2Discard" / "fmi3Discard": the table of
 * call names CF_CALL_NAMES of cf_messages.h); categories are those
 * of the model description's LogCategories
 * (logStatusWarning, logStatusDiscard, logStatusError, logStatusFatal, logAll). */
#ifndef CF_INSTANCE_H
#define CF_INSTANCE_H

#include <stddef.h>

#include "stepper.h" /* CF_HIDDEN */

typedef enum {
    CF_STATUS_OK = 0,
    CF_STATUS_WARNING = 1,
    CF_STATUS_DISCARD = 2,
    CF_STATUS_ERROR = 3,
    CF_STATUS_FATAL = 4
} cf_status;

/* The front end's callbacks. env: the instance's copy of the env_size bytes given to
 * cf_instantiate (during cf_instantiate, before the copy exists, the caller's bytes): a
 * front end keeps there what its callbacks need (FMI 2.0: the importer's
 * fmi2CallbackFunctions). log gets the message as text, never as a format; alloc(env, n,
 * size) gives n * size zeroed bytes or NULL, release(env, p) frees them. */
typedef struct {
    void (*log)(void *env, const char *instance, int status, const char *category,
                const char *message);
    void *(*alloc)(void *env, size_t n, size_t size);
    void (*release)(void *env, void *p);
} cf_callbacks;

typedef struct cf_inst cf_inst;

/* ---- lifetime ------------------------------------------------------------------------- */
/* A new instance at the start values; NULL with the reason logged (a GUID that is not
 * this FMU's, a creep-force table that cannot be read from resource_uri, no memory).
 * api: the prefix of the call and status names in messages, "fmi2" or "fmi3" (FMI 3.0's
 * call names), a string that outlives the instance; logging: whether CF_STATUS_OK messages are logged. */
CF_HIDDEN cf_inst *cf_instantiate(const char *api, const char *name, const char *guid,
                                  const char *resource_uri, int logging,
                                  const cf_callbacks *cb, void *env, size_t env_size);
/* Frees the instance and the FMU states it handed out that were not freed. */
CF_HIDDEN void cf_free_instance(cf_inst *I);
/* A message of the front end's own (a call this FMU does not provide), as the instance's
 * messages are logged; the text is a printf format. */
CF_HIDDEN void cf_log(const cf_inst *I, cf_status status, const char *fmt, ...);
/* The same before there is an instance (a refused instantiation). */
CF_HIDDEN void cf_log_to(const cf_callbacks *cb, void *env, const char *name, cf_status status,
                         const char *fmt, ...);
CF_HIDDEN void cf_set_debug_logging(cf_inst *I, int on);
/* the number of the model's variables: its value references are 0 ... n - 1 */
CF_HIDDEN unsigned cf_n_variables(void);

/* ---- phases ----------------------------------------------------------------------------- */
CF_HIDDEN cf_status cf_setup_experiment(cf_inst *I, double start_time);
CF_HIDDEN cf_status cf_enter_initialization_mode(cf_inst *I);
CF_HIDDEN cf_status cf_exit_initialization_mode(cf_inst *I);
CF_HIDDEN cf_status cf_terminate(cf_inst *I);
CF_HIDDEN cf_status cf_reset(cf_inst *I);

/* ---- variables: n value references vr, values v (both may be NULL where n is 0) ---------- */
CF_HIDDEN cf_status cf_get_real(cf_inst *I, const unsigned *vr, size_t n, double *v);
CF_HIDDEN cf_status cf_get_integer(cf_inst *I, const unsigned *vr, size_t n, int *v);
CF_HIDDEN cf_status cf_get_boolean(cf_inst *I, const unsigned *vr, size_t n); /* none here */
/* the strings handed out stay valid until the next cf_get_string of the instance */
CF_HIDDEN cf_status cf_get_string(cf_inst *I, const unsigned *vr, size_t n, const char **v);
CF_HIDDEN cf_status cf_set_real(cf_inst *I, const unsigned *vr, size_t n, const double *v);
CF_HIDDEN cf_status cf_set_integer(cf_inst *I, const unsigned *vr, size_t n, const int *v);
CF_HIDDEN cf_status cf_set_boolean(cf_inst *I, const unsigned *vr, size_t n); /* none here */
CF_HIDDEN cf_status cf_set_string(cf_inst *I, const unsigned *vr, size_t n,
                                  const char *const *v);

/* ---- the traction along the contact's centre line (FMI 3.0 arrays) ----------------------- */
/* the number of cells of the line's arrays, 0 where this FMU has none (rigid_body mode, a
 * creep-force table) */
CF_HIDDEN int cf_line_size(void);
/* which: 0 the cells' x (m, ascending), 1 tau_x, 2 tau_y (Pa) there, cf_line_size()
 * values into v, at the outputs' kinematics (layer.LayerContact.traction, ny = 1) */
CF_HIDDEN cf_status cf_get_line(cf_inst *I, int which, double *v);

/* ---- stepping ----------------------------------------------------------------------------- */
/* a communication step of h from t (t: the FMU's time, to 64 ulp) */
CF_HIDDEN cf_status cf_do_step(cf_inst *I, double t, double h);
/* the FMU's time: the end of the last step taken */
CF_HIDDEN double cf_time(const cf_inst *I);
/* the contact mode's d(outputs z)/d(inputs u) along du, nz outputs into dz */
CF_HIDDEN cf_status cf_directional_derivative(cf_inst *I, const unsigned *z, size_t nz,
                                              const unsigned *u, size_t nu, const double *du,
                                              double *dz);

/* ---- FMU states: opaque pointers handed out by the instance; a pointer that is not a
 * live state of this instance (freed, another instance's, anything else) is refused
 * without being read. ------------------------------------------------------------------- */
/* *state NULL: a new state; else a live state to overwrite */
CF_HIDDEN cf_status cf_get_state(cf_inst *I, void **state);
CF_HIDDEN cf_status cf_set_state(cf_inst *I, const void *state);
/* *state NULL: nothing to free (OK) */
CF_HIDDEN cf_status cf_free_state(cf_inst *I, void **state);
CF_HIDDEN cf_status cf_serialized_size(cf_inst *I, const void *state, size_t *size);
CF_HIDDEN cf_status cf_serialize(cf_inst *I, const void *state, unsigned char *out,
                                 size_t size);
/* bytes of cf_serialize into a state (*state NULL: new; else a live one overwritten) */
CF_HIDDEN cf_status cf_deserialize(cf_inst *I, const unsigned char *in, size_t size,
                                   void **state);

#endif
