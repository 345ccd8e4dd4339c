/*
 * stickslip_api.h: the JSON interface of stickslip.
 *
 * The api layer turns a request body into validated core structs, calls
 * libstickslip, and turns the result into a response body.  It knows JSON
 * (jansson) but not HTTP transport: the server routes a method and a path to
 * an endpoint of the table (api_route), hands it the body, and gets back a
 * status code, a media type and a body.  The contract is api/openapi.json.
 *
 * Errors are RFC 9457 problem details (application/problem+json):
 *   {"type", "title", "status", "detail", "pointer"?, "limit"?, "limit_value"?}
 * API_PROBLEM_MAP below is the only list of problem types and of the HTTP
 * status and title each one is answered with.
 */
#ifndef STICKSLIP_API_H
#define STICKSLIP_API_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/** Per-request limits; api_limits_default() gives the documented defaults. */
typedef struct api_limits {
  size_t max_body;        /**< request body bytes (server enforces) */
  size_t max_samples;     /**< samples in one response */
  size_t max_events;      /**< events computed by one /simulate */
  size_t max_event_list;  /**< events listed in one response */
  double max_horizon;     /**< t_end - t0, dimensionless time */
  double max_seconds;     /**< compute time of one request */
  int max_orbits;         /**< orbits in one /orbit response */
  int max_depth;          /**< JSON nesting depth */
  size_t max_batch_items; /**< requests in one /batch */
  size_t max_points;      /**< points of one /continue family */
  size_t max_map_cells;   /**< cells of one /map */
  size_t max_basin_cells; /**< cells of one /basins slice */
  unsigned map_threads;   /**< threads of one /map or /basins */
} api_limits;

/** Fill @a l with the defaults documented in the README. */
void api_limits_default(api_limits *l);

/** A large answer written as it is read (see api_server_info.stream_above). */
typedef struct api_stream api_stream;

/** A response: status, media type, and either a body (malloc'd,
 *  NUL-terminated) or a stream. */
typedef struct api_response {
  int status;
  char *body; /**< NULL when the answer is a stream */
  size_t len;
  const char *content_type; /**< static string */
  api_stream *stream;       /**< read with api_stream_read, or NULL */
  size_t held; /**< bytes the answer keeps in memory until it is freed */
} api_response;

/** Free the body or the stream; NULL-safe. */
void api_response_free(api_response *r);

/**
 * The next bytes of a streamed answer, at most @a max of them, into @a buf.
 * @return the number written (less than @a max only at the end), 0 once
 *         the answer is complete, -1 when out of memory.
 */
long api_stream_read(api_stream *s, char *buf, size_t max);

/** Free a stream (and the result it reads from); NULL-safe. */
void api_stream_free(api_stream *s);

/* ------------------------------------------------------------------------ */
/* The endpoint table                                                        */
/* ------------------------------------------------------------------------ */

/** How an endpoint is served. */
typedef enum api_run_class {
  /** Cheap and body-less (GET): answered on the connection's own thread. */
  API_RUN_INLINE = 0,
  /** A POST whose JSON body asks for a computation: it takes a compute
   *  slot, and the computation is bounded by api_limits.max_seconds. */
  API_RUN_COMPUTE = 1,
  /** A POST whose JSON body lists computations (POST /batch): a server
   *  runs them one by one (api_batch_open and the functions after it);
   *  api_handle runs them in order and answers the whole NDJSON text. */
  API_RUN_BATCH = 2
} api_run_class;

/** The public view of one row of the endpoint table (api/src/endpoints.h). */
typedef struct api_endpoint {
  const char *method; /**< "GET" or "POST" */
  const char *path;   /**< e.g. "/orbit" */
  const char *label;  /**< its name in metrics and logs, e.g. "orbit" */
  api_run_class run_class;
} api_endpoint;

/** The number of endpoints; they are numbered 0 .. api_endpoint_count()-1. */
size_t api_endpoint_count(void);

/** Row @a i of the table; NULL when @a i is out of range. */
const api_endpoint *api_endpoint_at(size_t i);

/**
 * Route a request line.  HEAD is served as GET.
 * @param[out] index  the endpoint: on 200 the one to call; on 405 the one
 *                    that owns @a path (its method is the Allow header)
 * @return 200 (found), 404 (no such path) or 405 (path known, method not).
 */
int api_route(const char *method, const char *path, size_t *index);

/** What the server tells the api about itself, for the meta endpoints. */
typedef struct api_server_info {
  double uptime_seconds;
  long in_flight;        /**< requests being served */
  const char *transport; /**< e.g. the HTTP library's version, may be NULL */
  /** The Prometheus text of the server's metrics (malloc'd; NULL when out of
   *  memory); NULL when the server keeps none. */
  char *(*metrics_text)(void *cls);
  void *metrics_cls;
  /** Whether the client has gone away: polled by long computations, which
   *  then stop (answered client-closed-request, which nobody reads).  NULL:
   *  never. */
  int (*cancelled)(void *cls);
  void *cancel_cls;
  /** Answers whose large arrays (samples, events) hold more than this many
   *  bytes are streamed (api_response.stream) instead of written whole;
   *  0: never. */
  size_t stream_above;
  /** How many threads a computation that runs on several (/map, /basins)
   *  may use, of the @a want it would (api_limits.map_threads), its own
   *  included: at least 1.  The server counts the others as the client's
   *  computations until the request ends.  NULL: @a want. */
  unsigned (*threads)(void *cls, unsigned want);
  void *threads_cls;
  /** Serve a computing request only when its work is small and bounded,
   *  microseconds whatever its numbers (an /orbit from a guess without
   *  samples, a /stability); any other is left: api_handle answers status
   *  0, @a out empty, for the server to run where long work runs. */
  int small_only;
  /** The form of the answer the client asked for (api_negotiate). */
  int form;
} api_server_info;

/** The forms of an answer: the endpoint's own (JSON; NDJSON for /map and
 *  /batch), or NDJSON for an endpoint that answers in it besides JSON
 *  (POST /basins: its rows as they are done, then its summary). */
typedef enum api_form { API_FORM_DEFAULT = 0, API_FORM_NDJSON = 1 } api_form;

/**
 * The form in which endpoint @a index answers a client whose Accept header
 * is @a accept (NULL: none): API_FORM_NDJSON when the endpoint has that
 * form besides JSON and @a accept names application/x-ndjson with a
 * quality above 0 and above that of application/json; otherwise
 * API_FORM_DEFAULT (JSON stays the default).
 */
api_form api_negotiate(size_t index, const char *accept);

/**
 * Serve endpoint @a index: for API_RUN_COMPUTE, parse, validate, compute and
 * encode @a body; for API_RUN_INLINE, @a body is ignored.  Always fills
 * @a out (a result or a problem), unless @a srv->small_only leaves the
 * request (status 0); returns out->status.  @a srv may be NULL
 * (the meta endpoints then report what they can).  Thread-safe.
 */
int api_handle(size_t index, const char *body, size_t len,
               const api_limits *lim, const api_server_info *srv,
               api_response *out);

/* ------------------------------------------------------------------------ */
/* Batches (POST /batch)                                                     */
/* ------------------------------------------------------------------------ */

/*
 * A batch is {"requests": [{"id": ..., "path": "/orbit", "body": {...}},
 * ...]}.  Its answer is NDJSON (application/x-ndjson): one line
 *   {"id": ..., "index": i, "status": S, "body": {...}}
 * per item, in the order the items are done, and a last line
 *   {"done": true, "ok": N, "failed": M, "seconds": S}.
 * An item that is not well formed (no such path, no body) is answered by
 * its own line with its problem; the others go on.  A problem's pointer in
 * an item's line is relative to the item ("/path", "/body/params/chi").
 */
typedef struct api_batch api_batch;

/** Parse and check a batch.  0 and *b; or -1, *b NULL, and the problem in
 *  @a out (the batch as a whole is refused). */
int api_batch_open(const char *body, size_t len, const api_limits *lim,
                   api_batch **b, api_response *out);
/** The number of items. */
size_t api_batch_size(const api_batch *b);
/** The endpoint index of item @a i (as api_route gives it), or
 *  api_endpoint_count() when its path names no endpoint a batch takes. */
size_t api_batch_endpoint(const api_batch *b, size_t i);
/** The bytes the batch keeps until it is freed (its items' bodies). */
size_t api_batch_held(const api_batch *b);
/** Serve item @a i: its answer, or its problem, in @a out (as api_handle;
 *  thread-safe for distinct items).  Returns out->status. */
int api_batch_run(api_batch *b, size_t i, const api_limits *lim,
                  const api_server_info *srv, api_response *out);
/** The line of item @a i, whose answer is @a item (consumed, whatever
 *  happens; made by api_batch_run or api_problem), as a stream of one
 *  line that ends with a newline: an NDJSON answer (a /map's) is carried as
 *  the array of its lines.  *held: the bytes it keeps.  NULL when out of
 *  memory. */
api_stream *api_batch_line(const api_batch *b, size_t i, api_response *item,
                           size_t *held);
/** The same line appended to the text *buf (*len bytes of *cap allocated,
 *  grown with realloc; the caller frees it), for an answer @a item that is
 *  a body: no stream, no allocation of its own.  1 appended (@a item
 *  consumed); 0 when @a item is a stream (left as it is, for
 *  api_batch_line); -1 when out of memory (@a item consumed, *len as it
 *  was). */
int api_batch_line_put(const api_batch *b, size_t i, api_response *item,
                       char **buf, size_t *len, size_t *cap);
/** The last line (a body, malloc'd, in @a out). */
void api_batch_done(size_t ok, size_t failed, double seconds,
                    api_response *out);
/** Free a batch; NULL-safe. */
void api_batch_free(api_batch *b);

/* ------------------------------------------------------------------------ */
/* Jobs (Prefer: respond-async)                                              */
/* ------------------------------------------------------------------------ */

/*
 * A job is a computing request (an endpoint of class API_RUN_COMPUTE or
 * API_RUN_BATCH) answered later.  The api cuts it into chunks, each computed
 * on its own (by any replica, in any order its stages allow) into a result
 * that the server stores; the job's answer is then made of the stored
 * results alone:
 *   answer = the results of the visible chunks, in chunk order, concatenated
 * and it is byte for byte what the synchronous request answers (but for a
 * time it reports, "seconds").  A chunk that is not visible is work that
 * later chunks read (api_job_inputs): a /map's full searches, read by the
 * chunk that spreads them.  Chunks come in stages: every chunk of stage s
 * may read the results of every chunk of the stages before it, and starts
 * once they are all stored.
 *
 * The cuts: a single answer (/orbit, /simulate, /stability, /continue) is
 * one visible chunk; a /batch's items are cut in groups of consecutive
 * items (each chunk: their lines), and a last chunk writes the done line;
 * a /map's full searches of its lattice are cut in groups, and a last
 * chunk spreads them and writes the answer; a /basins' rows of cells are
 * cut in groups (in its NDJSON form, api_job_open_form, each group's
 * result is a line of the answer, so its results grow as they are
 * stored).  Progress is told in items: batch items, map or basin cells
 * (api_job_items).
 */
typedef struct api_job api_job;

/**
 * Parse and check a job's request as the synchronous endpoint @a index
 * would (the same problems, answered at submission), and cut it.  The same
 * body gives the same cuts in every process.  0 and *j; or -1, *j NULL and
 * the problem in @a out.
 */
int api_job_open(size_t index, const char *body, size_t len,
                 const api_limits *lim, api_job **j, api_response *out);
/** api_job_open for an answer in @a form (api_negotiate): the same cuts
 *  for API_FORM_DEFAULT; an endpoint's other form is cut its own way. */
int api_job_open_form(size_t index, api_form form, const char *body, size_t len,
                      const api_limits *lim, api_job **j, api_response *out);
/** Free a job; NULL-safe. */
void api_job_free(api_job *j);
/** The number of chunks (at least 1). */
size_t api_job_chunks(const api_job *j);
/** The stage of chunk @a k (0 for the first; stages never decrease with k). */
int api_job_stage(const api_job *j, size_t k);
/** What chunk @a k adds to the items done. */
long api_job_chunk_items(const api_job *j, size_t k);
/** The items of the whole job (the sum over its chunks). */
long api_job_items(const api_job *j);
/** Whether chunk @a k's result is part of the answer. */
int api_job_visible(const api_job *j, size_t k);
/** The media type of the answer ("application/json" or
 *  "application/x-ndjson"). */
const char *api_job_content_type(const api_job *j);
/** The bytes the job keeps until it is freed. */
size_t api_job_held(const api_job *j);

/** How a chunk reads the stored results of the chunks of earlier stages. */
typedef struct api_job_inputs {
  /** Chunk @a k's result into *buf (malloc'd by the reader, freed by the
   *  caller): 0, or -1 when it cannot be read. */
  int (*read)(void *cls, size_t k, char **buf, size_t *len);
  void *cls;
  /** When the job started (epoch seconds, as api_job_info.started), for
   *  the time its answer reports (a /batch's done line: the seconds since);
   *  0 when not known (the time is then 0). */
  double started;
} api_job_inputs;

/**
 * Compute chunk @a k.  200 and its result in out->body (the bytes to store;
 * out->len of them); or a problem in @a out (its status), which fails the
 * job: the job's answer is then that problem.  lim->max_seconds bounds the
 * chunk (a server sets it from its job limit); srv->cancelled stops it.
 * Thread-safe for distinct chunks.  Returns out->status.
 */
int api_job_run(api_job *j, size_t k, const api_job_inputs *in,
                const api_limits *lim, const api_server_info *srv,
                api_response *out);

/** What a server tells of a job, for api_job_status_json. */
typedef struct api_job_info {
  const char *id, *path;
  const char *status; /**< "accepted", "running", "successful", "failed",
                           "dismissed" */
  double created, started, updated, finished; /**< epoch seconds; 0: not */
  long items, items_done;
  long chunks, chunks_done;
  const char *message; /**< may be NULL */
} api_job_info;

/** The status document of a job, {"id", "path", "status", "progress",
 *  "created", ..., "items": {"done", "total"}, "message", "links"} (OGC API
 *  - Processes' statusInfo, with links to itself and its results): 200 in
 *  @a out.  OGC's own names are there too ("jobID", "type": "process",
 *  "processID": the path without its slash); a time is RFC 3339 in UTC to
 *  the millisecond, absent while it has not happened; "progress" is 0-100
 *  from the items (from the chunks when there are none), 100 only once
 *  the job is successful; "message" is @a info->message, or the items done
 *  when NULL; the results' link has OGC's relation
 *  http://www.opengis.net/def/rel/ogc/1.0/results. */
int api_job_status_json(const api_job_info *info, api_response *out);
/** The list of jobs, newest first ({"jobs": [...], "links", "total"}):
 *  @a n of them from the @a offset-th of @a total; its links (rel self,
 *  next while jobs follow, prev after the first page) are
 *  /jobs?offset=O&limit=L with @a limit.  200 in @a out. */
int api_job_list_json(const api_job_info *jobs, size_t n, long offset,
                      long limit, long total, api_response *out);

/* ------------------------------------------------------------------------ */
/* Problems                                                                  */
/* ------------------------------------------------------------------------ */

/*
 * The one table of problem types: name, HTTP status, type (the tail of
 * "/problems/<type>"), title.  Core statuses are mapped onto these rows by
 * the table API_STATUS_PROBLEM in api/src/problem.c, the only place that
 * mapping is written.
 */
#define API_PROBLEM_MAP(X)                                                     \
  X(INVALID_JSON, 400, "invalid-json", "Bad Request")                          \
  X(BAD_REQUEST, 400, "bad-request", "Bad Request")                            \
  X(NOT_FOUND, 404, "not-found", "Not Found")                                  \
  X(METHOD_NOT_ALLOWED, 405, "method-not-allowed", "Method Not Allowed")       \
  X(BODY_TOO_LARGE, 413, "limit-exceeded", "Content Too Large")                \
  X(MEDIA_TYPE, 415, "unsupported-media-type", "Unsupported Media Type")       \
  X(INVALID_TYPE, 422, "invalid-type", "Unprocessable Content")                \
  X(INVALID_VALUE, 422, "invalid-value", "Unprocessable Content")              \
  X(MISSING_FIELD, 422, "missing-field", "Unprocessable Content")              \
  X(UNKNOWN_FIELD, 422, "unknown-field", "Unprocessable Content")              \
  X(NO_CONVERGENCE, 422, "no-convergence", "Unprocessable Content")            \
  X(LIMIT, 422, "limit-exceeded", "Request over a limit")                      \
  X(CLIENT_CLOSED, 499, "client-closed-request", "Client Closed Request")      \
  X(INTERNAL, 500, "internal", "Internal Server Error")                        \
  X(OVERLOADED, 503, "overloaded", "Service Unavailable")                      \
  X(OUT_OF_MEMORY, 503, "out-of-memory", "Service Unavailable")                \
  X(SHUTTING_DOWN, 503, "shutting-down", "Service Unavailable")                \
  X(STORE_UNAVAILABLE, 503, "store-unavailable", "Service Unavailable")

/** The problem types, in the order of API_PROBLEM_MAP. */
typedef enum api_problem_kind {
#define API_PROBLEM_ENUM(name, status, type, title) API_P_##name,
  API_PROBLEM_MAP(API_PROBLEM_ENUM)
#undef API_PROBLEM_ENUM
      API_P_COUNT
} api_problem_kind;

/** The HTTP status of a problem type (500 for an unknown one). */
int api_problem_status(api_problem_kind kind);

/**
 * A problem response built by the caller (transport errors: 404, 405, 413,
 * 415, 503).  @a detail, @a pointer and @a limit may be NULL; @a limit
 * names the limit that was hit, @a limit_value its value.
 */
void api_problem(api_response *out, api_problem_kind kind, const char *detail,
                 const char *pointer, const char *limit, double limit_value);

/** The type of a problem kind, the tail of its "/problems/<type>" URI
 *  ("invalid-value"); NULL for an unknown kind. */
const char *api_problem_type(api_problem_kind kind);

/** The number of problem types that have a page: one per distinct type of
 *  API_PROBLEM_MAP. */
size_t api_problem_page_count(void);

/** The type of page @a i ("invalid-value"); NULL when @a i is out of
 *  range. */
const char *api_problem_page_type(size_t i);

/**
 * The page of problem type @a type (the tail of "/problems/<type>"), what
 * GET /problems/<type> answers: its title, HTTP statuses, what it means and
 * how to fix the request; as an HTML document when @a html, else as JSON
 * {"type", "title", "status": [..], "meaning", "fix"}.  200; or 404, a
 * not-found problem, for a type that is not one.  Always fills @a out.
 */
int api_problem_page(const char *type, int html, api_response *out);

/** The OpenAPI document (api/openapi.json, with the project's version). */
const char *api_openapi_json(void);

/** The explorer's embedded files (api/explorer): "index.html", "app.js" or
 *  "style.css", their length into *len; NULL for another name. */
const char *api_explorer_asset(const char *name, size_t *len);

/** Whether this build embeds the user's guide (docs/, built by mkdocs when
 *  it was installed at build time). */
int api_docs_built(void);

/**
 * A file of the embedded user's guide by its @a path under the guide's root
 * ("index.html", "api/orbit.html", "css/base.css"; a path ending in "/" is
 * its index.html): its bytes (the same for the life of the binary), their
 * length into *len, its media type into *ctype and a validator (a quoted
 * ETag) into *etag; NULL when the guide has no such file.
 */
const char *api_docs_file(const char *path, size_t *len, const char **ctype,
                          const char **etag);

/**
 * The body of row @a i when it is static (the contract and the explorer's
 * files: the same bytes for the life of the binary, so that a server can
 * give them a validator and a lifetime), its length into *len; NULL for a
 * row whose answer is computed.
 */
const char *api_static_body(size_t i, size_t *len);

/** The version string of the service (the library's SS_VERSION). */
const char *api_version(void);

#ifdef __cplusplus
}
#endif

#endif
