/*
 * decode.h: requests decoded from their declarative specs (decode.c): the
 * field descriptions, the parameters every computing endpoint shares, phase
 * sequences and guesses, the echo of a decoded request, and the units of a
 * request.
 */
#ifndef SS_API_DECODE_H
#define SS_API_DECODE_H

#include <jansson.h>
#include <stddef.h>

#include "call.h"
#include "stickslip.h"

/* ---- declarative request specs ----------------------------------------- */

typedef enum api_type {
  API_T_ANY,    /* accepted and ignored (a key of an object echoed back) */
  API_T_NUMBER, /* double, finite, in [lo, hi] */
  API_T_COUNT,  /* integer in [lo, hi] (long long) */
  API_T_BOOL,   /* true or false (int) */
  API_T_ENUM,   /* one of the strings in aux (int index) */
  API_T_VEC4,   /* four finite numbers (double[4]) */
  API_T_OBJECT, /* an object described by the spec in aux */
  API_T_CUSTOM  /* decoded and echoed by the api_custom in aux */
} api_type;

enum {
  API_REQUIRED = 1,  /* missing is an error (in its alternative, if any) */
  API_ECHO_NEVER = 2 /* not echoed in the response's "input" */
};

/* Echo rule: a field is echoed when it was given, is required outside any
 * alternative, or has a default (API_DEFAULT); otherwise it is left out. */
enum { API_DEFAULT = 4 };

typedef struct api_field api_field;

/* A field whose value needs code: arrays of modes, of times, of phases. */
typedef struct api_custom {
  int (*decode)(const json_t *v, const char *ptr, void *dest,
                const api_call *c);
  json_t *(*echo)(const void *dest);
} api_custom;

/* An object: its fields, in the order they are checked and echoed. */
typedef struct api_spec {
  const api_field *fields;
  int n;
} api_spec;

struct api_field {
  const char *name;
  api_type type;
  unsigned flags;
  double lo, hi;     /* NUMBER, COUNT: the accepted range, inclusive */
  const char *limit; /* COUNT: the api_limits field bounding it, by name */
  size_t off;        /* where the value goes, from the struct's start */
  size_t has;        /* 1 + offset of an int set to 1 when given; 0: none */
  int group, alt;    /* group > 0: exactly one alternative of the group */
  const void *aux;   /* ENUM: const char *const[] (NULL-terminated);
                        OBJECT: const api_spec *; CUSTOM: const api_custom * */
};

#define API_HAS(type, member) (offsetof(type, member) + 1)
#define API_SPEC(fields)                                                       \
  { fields, (int)(sizeof fields / sizeof fields[0]) }

/*
 * Decode the object @a obj at JSON pointer @a ptr by @a spec into @a dest:
 * unknown keys are refused (the message lists the known ones), each group
 * must have exactly one alternative, required fields must be present, and
 * every value must have its type and range.  Returns 0 or -1 (problem in
 * c->e).
 */
int api__decode(const api_spec *spec, const json_t *obj, const char *ptr,
                void *dest, const api_call *c);

/* The echo of a decoded object: the fields given or with a default, in
 * spec order, from @a dest (the units are the request's). */
json_t *api__echo(const api_spec *spec, const void *dest);

/* Whether the field @a name of a decoded struct was given. */
int api__given(const api_spec *spec, const void *dest, const char *name);

/* The numbers of the JSON array @a v into @a out (room for all of them);
 * an element that is not a finite number is an error at @a ptr. */
int api__numbers(const json_t *v, const char *ptr, double *out, api_err *e);

/* ---- parameters shared by every computing endpoint --------------------- */

/* "params" or "physical", as given, and the dimensionless parameters with
 * the time scale omega (1 when dimensionless). */
typedef struct api_params {
  ss_params p;
  ss_physical ph;
  int has_params, has_physical;
  double omega;
} api_params;

/* The two fields "params" and "physical" (group 1), for an endpoint's spec;
 * @a type is the endpoint's request struct, @a m its api_params member. */
extern const api_spec API_PARAMS_SPEC, API_PHYSICAL_SPEC;
/* The names a request gives a parameter by, NULL-terminated: the
 * dimensionless ones (ss_param_id), then the physical ones (ss_phys_id +
 * API_N_DIMENSIONLESS), from the core's lists. */
extern const char *const API_PARAMETER_NAMES[];
enum { API_N_DIMENSIONLESS = SS_PARAM_V + 1 };
#define API_PARAMS_FIELDS(type, m)                                             \
  {"params",                                                                   \
   API_T_OBJECT,                                                               \
   API_REQUIRED | API_ECHO_NEVER,                                              \
   0,                                                                          \
   0,                                                                          \
   NULL,                                                                       \
   offsetof(type, m) + offsetof(api_params, p),                                \
   API_HAS(type, m.has_params),                                                \
   1,                                                                          \
   0,                                                                          \
   &API_PARAMS_SPEC},                                                          \
  {                                                                            \
    "physical", API_T_OBJECT, API_REQUIRED | API_ECHO_NEVER, 0, 0, NULL,       \
        offsetof(type, m) + offsetof(api_params, ph),                          \
        API_HAS(type, m.has_physical), 1, 1, &API_PHYSICAL_SPEC                \
  }

/* A key that is accepted and not read. */
#define API_ANY(name)                                                          \
  { name, API_T_ANY }

/* Any other key of the object accepted and ignored: an object the daemon
 * answered with, sent back, stays open (its own objects, such as an orbit's
 * phases, keep their specs). */
#define API_OTHER_KEYS API_ANY("*")

/* The fields of an orbit object, as /orbit or /basins returns it, so that a
 * client may send an orbit back as it got it, with keys of its own added:
 * x0, z0 and phases as the endpoint reads them (API_ANY where it does not),
 * every other key accepted and ignored. */
#define API_ORBIT_FIELDS(x0, z0, phases) x0, z0, phases, API_OTHER_KEYS

/* Phase sequences: durations (2 to SS_MAX_PHASES numbers > 0) and modes
 * (as many mode names), as fields of a spec. */
typedef struct api_durations {
  double v[SS_MAX_PHASES];
  int n;
} api_durations;
typedef struct api_modes {
  ss_mode m[SS_MAX_PHASES];
  int n;
} api_modes;
extern const api_custom API_DURATIONS, API_MODES;

/* "phases": [{"mode", "duration"}, ...], 2 to SS_MAX_PHASES of them, a
 * sequence api__sequence accepts (API_PHASES decodes and echoes it). */
typedef struct api_phases {
  api_modes modes;
  api_durations dur;
} api_phases;
extern const api_custom API_PHASES;

/* "guess": {"durations": [...], "modes": [...]} (API_GUESS_SPEC); the modes
 * default to the overshoot or stick-slip sequence by the number of
 * durations, which api__guess_modes fills in and checks (@a ptr is the
 * guess's pointer).  0 or -1. */
typedef struct api_guess {
  api_durations durations;
  api_modes modes;
  int has_modes;
} api_guess;
extern const api_spec API_GUESS_SPEC;
int api__guess_modes(api_guess *g, const char *ptr, const api_call *c);

/* "slip", "overshoot", "stick" to a mode; -1 for anything else. */
int api__mode_of(const char *s, ss_mode *m);

/* The rules every orbit's sequence obeys: it starts with slip (at the
 * stick -> slip point), ends with stick, and never repeats a mode in two
 * consecutive phases.  @a ptr is the pointer of the array.  0 or -1. */
int api__sequence(const api_modes *s, const char *ptr, const api_call *c);

/* After api__decode: check the parameters with the core and derive the
 * dimensionless ones and omega.  Returns 0 or -1. */
int api__params_resolve(api_params *ap, const api_call *c);

/* The steps every computing endpoint's decode shares: its struct allocated
 * (zeroed) in *xp, NULL when out of memory; the body decoded by @a spec with
 * the parameters resolved; the model of the parameters initialised. */
void *api__alloc(size_t size, void **xp, const api_call *c);
int api__decode_request(const api_spec *spec, const json_t *root, void *x,
                        api_params *ap, const api_call *c);
int api__model(ss_model *m, const api_params *ap, const api_call *c);

/* The echo of the parameters: "params" (dimensionless), and for a physical
 * request "physical" and "omega"; added to @a in. */
void api__params_echo(json_t *in, const api_params *ap);

/* api__echo, with (@a ap not NULL) the members api__params_echo adds,
 * as a lazy value: its text written from @a dest when the answer is, the
 * bytes api__echo's tree dumps to without the tree (a dozen objects and
 * their keys for each answer).  @a dest and @a ap must live as long as the
 * answer is being written (the endpoint's struct). */
json_t *api__echo_raw(const api_call *c, const api_spec *spec, const void *dest,
                      const api_params *ap);
/* That text, written now to @a w. */
struct api_wbuf;
void api__w_echo(struct api_wbuf *w, const api_spec *spec, const void *dest,
                 const api_params *ap);
/* For tests: not 0 has the answers build their echo as a tree of values
 * (api__echo and api__params_echo) and write that, the text the written
 * echo must equal (tests/api/test_echo.c). */
extern int api__echo_as_tree;

/* ---- units: every conversion of a request goes through these ----------- */

/* A time of the request in dimensionless time, and back. */
static inline double api__time_in(const api_params *ap, double t) {
  return t * ap->omega;
}
static inline double api__time_out(const api_params *ap, double t) {
  return t / ap->omega;
}

#endif
