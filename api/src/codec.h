/*
 * codec.h: internal helpers of the api layer: problems, declarative request
 * specs with JSON pointers, the parameters every endpoint shares, and the
 * encoding helpers.
 */
#ifndef SS_API_CODEC_H
#define SS_API_CODEC_H

#include <jansson.h>
#include <stdint.h>
#include <stddef.h>

#include "stickslip.h"
#include "stickslip_api.h"

#define API_FORMAT(a, b)
#ifdef __GNUC__
#undef API_FORMAT
#define API_FORMAT(a, b) __attribute__((format(printf, a, b)))
#endif

/* ---- problems ----------------------------------------------------------- */

/* A problem being built; the first failure wins. */
typedef struct api_err {
  int set;
  api_problem_kind kind;
  char detail[400];
  char pointer[160];
  char limit[32];
  double limit_value;
} api_err;

/* Record a problem of @a kind at @a pointer (may be NULL); returns -1. */
int api__fail(api_err *e, api_problem_kind kind, const char *pointer,
              const char *fmt, ...) API_FORMAT(4, 5);

/* A request over the limit named @a limit (its value @a value); returns -1. */
int api__limit(api_err *e, const char *limit, double value, const char *pointer,
               const char *fmt, ...) API_FORMAT(5, 6);

/* A failure status of the core that is a limit: as api__status, and the
 * problem names the limit @a limit and its value. */
int api__status_limit(api_err *e, int status, const char *limit, double value,
                      const char *pointer, const char *fmt, ...)
    API_FORMAT(6, 7);

/* A failure status of the core, answered by the table API_STATUS_PROBLEM;
 * a status the table does not know is an internal error.  @a pointer names
 * the field at fault (may be NULL).  Returns -1. */
int api__status(api_err *e, int status, const char *pointer, const char *fmt,
                ...) API_FORMAT(4, 5);

/* The core's diagnostic as a problem: the pointer is @a base followed by the
 * diagnostic's "where" (a parameter name), the detail is its text. */
int api__from_diag(api_err *e, int rc, const ss_diag *d, const char *base);

/* The response for a recorded problem. */
void api__problem_response(const api_err *e, api_response *out);

/* ---- one call of an endpoint ------------------------------------------- */

typedef struct api_lazies api_lazies;

typedef struct api_call {
  const api_limits *lim;
  const api_server_info *srv; /* may be NULL */
  api_err *e;
  api_lazies *lazy; /* the answer's lazy arrays (writer.c) */
} api_call;

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

/* The fields of an orbit object, as /orbit returns it, so that a client may
 * send an orbit back as it got it: x0, z0 and phases as the endpoint reads
 * them (API_ANY where it does not), every other key accepted and ignored. */
#define API_ORBIT_FIELDS(x0, z0, phases)                                       \
  x0, z0, phases, API_ANY("kind"), API_ANY("period"), API_ANY("n_turns"),      \
      API_ANY("margins"), API_ANY("residual"), API_ANY("closure"),             \
      API_ANY("stability"), API_ANY("samples"), API_ANY("source"),             \
      API_ANY("iterations")

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

/* ---- units: every conversion of a request goes through these ----------- */

/* A time of the request in dimensionless time, and back. */
static inline double api__time_in(const api_params *ap, double t) {
  return t * ap->omega;
}
static inline double api__time_out(const api_params *ap, double t) {
  return t / ap->omega;
}

/* ---- encoding ---------------------------------------------------------- */

/* Helpers that never emit NaN or Infinity: a non-finite value becomes
 * null. */
json_t *api__real(double v);
json_t *api__vec4(const double x[4]);
json_t *api__vec(const double *x, int n);
int api__set(json_t *obj, const char *key, json_t *v);

/* A state in the request's units. */
json_t *api__state(const api_params *ap, const double x[4]);

/* Finish a computing answer @a out (consumed): the echo of the request
 * @a x by @a spec with its parameters as "input", the "units" and the
 * "version"; then the 200 response. */
int api__answer(json_t *out, const api_spec *spec, const void *x,
                const api_params *ap, const api_call *c, api_response *resp);

/* The samples of a simulation as columns t, x1, x2, v1, v2, mode, in the
 * units of the request: lazy arrays read from @a r when the answer is
 * written, so @a r must live as long as the answer (it is part of the
 * endpoint's struct). */
json_t *api__samples(const ss_sim_result *r, const api_params *ap,
                     unsigned columns, const api_call *c);

/* ---- what a request asks of its samples (samples.c) ---- */

/* Sample times as given (malloc'd). */
typedef struct api_times {
  double *v;
  size_t n;
} api_times;

/* "samples": {"n", "from", "to"}, {"t": [...]}, or {"tolerance", "plane",
 * "scale", "max", "from", "to"}; with any, "fields" (the columns). */
typedef struct api_samples_req {
  long long n, max;
  double from, to, tolerance;
  double scale[4]; /* of x1, x2, v1, v2; 0: 1 */
  unsigned plane;  /* bits of x1, x2, v1, v2 */
  unsigned fields; /* bits of API_SAMPLE_COLUMNS */
  api_times t;
  int has_n, has_from, has_to, has_t, has_tolerance, has_plane, has_scale,
      has_max, has_fields;
} api_samples_req;

/* t, x1, x2, v1, v2, mode, force, F1, F2 (NULL-terminated). */
extern const char *const API_SAMPLE_COLUMNS[];
/* The object's spec in /simulate (all of it) and in /orbit (n, or a
 * tolerance; over one period). */
extern const api_spec API_SIM_SAMPLES, API_ORBIT_SAMPLES;

/* The tolerance, axes, scales and count limit of a curve's samples into
 * @a o (nothing for even samples or times), after the checks that span
 * fields; @a ptr is the object's pointer.  0 or -1 (problem in c->e). */
int api__samples_core(const api_samples_req *s, const api_params *ap,
                      const char *ptr, ss_sim_opts *o, const api_call *c);
/* The columns asked for, as bits of API_SAMPLE_COLUMNS. */
unsigned api__samples_columns(const api_samples_req *s);
void api__samples_release(api_samples_req *s);

/* The phases of an orbit [{mode, duration}] in the units of the request. */
json_t *api__phases(int n, const ss_mode *modes, const double *tau,
                    const api_params *ap);

/* The Jacobian of the Poincare map, and the whole stability object, in the
 * request's units. */
json_t *api__jacobian(const double J[2][2], const api_params *ap);
json_t *api__stability(const ss_stab *st, const api_params *ap);

/* ---- the writer (writer.c) --------------------------------------------- */

typedef struct api_wbuf {
  char *p;
  size_t len, cap;
  int oom;
} api_wbuf;

/* Append bytes, a JSON string, a number (shortest exact digits; null when
 * not finite). */
void api__w_put(api_wbuf *b, const char *s, size_t n);
void api__w_str(api_wbuf *b, const char *s, size_t n);
void api__w_real(api_wbuf *b, double v);
/* @a v, finite, as few digits as read back as v, or one more (shortest.c),
 * written as printf's %g writes them, with ".0" added to a whole number,
 * into @a out (32 bytes); the length. */
int api__shortest(double v, char *out);
/* Entry @a i of the cached powers of ten: 10^k ~ f * 2^e, k returned
 * (0 when @a i is past the table). */
int api__pow10_cached(int i, uint64_t *f, int *e);
/* The shortest digits of the finite, nonzero |v| (v = digits * 10^k) by
 * Grisu3 alone: their count, or 0 when it cannot be sure. */
int api__grisu3(double v, char *digits, int *k);
#define API_W_LIT(b, lit) api__w_put(b, lit, sizeof(lit) - 1)

/* A lazy array: n elements, element i written by item() from a, b, k. */
typedef struct api_lazy api_lazy;
typedef void api_item_fn(api_wbuf *w, const api_lazy *l, size_t i);
struct api_lazy {
  const json_t *marker;
  api_item_fn *item;
  const void *a, *b;
  int k;
  size_t n;
};
struct api_lazies {
  api_lazy *v;
  size_t n, cap;
  size_t held; /* bytes of the arrays they are read from */
};

/* The marker of a lazy array of @a n elements, to be put in the answer's
 * tree where the array goes (NULL when out of memory).  What @a a and @a b
 * point to must live as long as the endpoint's struct.  @a held: the bytes
 * of the core arrays it reads, which a streamed answer keeps. */
json_t *api__lazy(const api_call *c, size_t n, api_item_fn *item, const void *a,
                  const void *b, int k, size_t held);
void api__lazies_free(api_lazies *lz);

/* A 200 application/json answer with the body of @a j (consumed): written
 * whole, or a stream when its lazy arrays are larger than the server's
 * stream_above (the caller then hands the stream the endpoint's struct with
 * api__stream_own). */
int api__json_response(json_t *j, const api_call *c, api_response *out);
void api__stream_own(api_stream *s, void *x, void (*release)(void *));

/* A stream of @a head (malloc'd, consumed), the answer @a r (consumed: its
 * body, or its stream read as it goes) and @a tail (copied); NULL when out
 * of memory (everything given is freed). */
api_stream *api__stream_wrap(char *head, size_t head_len, api_response *r,
                             const char *tail);

/* A request body as a JSON object (nesting depth at most lim->max_depth,
 * no duplicate keys), or NULL with the problem in @a e. */
json_t *api__parse(const char *body, size_t len, const api_limits *lim,
                   api_err *e);

/* Serve endpoint @a index as api_handle does; a problem's pointer, when it
 * names a field, is prefixed by @a prefix (NULL: none), for an answer read
 * as part of a larger document (an item of a batch). */
int api__handle(size_t index, const char *body, size_t len,
                const api_limits *lim, const api_server_info *srv,
                api_response *out, const char *prefix);

/* The compact text of @a j (malloc'd, NUL-terminated, length in *len), with
 * reals in the shortest of 15-17 significant digits that reads back exactly;
 * NULL when out of memory.  Strings must be valid UTF-8 (jansson's own). */
char *api__dump(const json_t *j, size_t *len);

#endif
