/*
 * internal.h: what the daemon's files share; not installed.
 *
 *   daemon.c   start and stop: listening, descriptors, the daemon's info
 *   request.c  a request: admission, body, the pool's side, completion
 *   reply.c    answers: headers, CORS, gzip, streams, problems, the budget
 *   batch.c    POST /batch: body parsed, and items run, in the pool; lines
 *              streamed as done
 *   jobs.c     jobs: the store, the runners that compute their chunks, the
 *              ticker (leases, cancellation, expiry, waiting streams)
 *   jobs_http.c  jobs over HTTP: Prefer: respond-async, /jobs, its
 *              results streamed as they are stored
 *   monitor.c  connections: tracking, admission by address, slow clients,
 *              peers gone away
 *   tally.c    counts by client: bytes held, connections
 *   wire.c     the bytes libmicrohttpd reads, followed: a chunk line too
 *              long for it answered 413
 */
#ifndef SS_SERVER_INTERNAL_H
#define SS_SERVER_INTERNAL_H

#include <pthread.h>
#include <stdatomic.h>
#include <stddef.h>

#include <microhttpd.h>

#include "server.h"
#include "store.h"

/* bytes of a streamed answer at a time */
#define SRV__STREAM_CHUNK (32 * 1024)
/* gzip at a level that keeps it cheap next to the computation (a
 * 2000-sample /simulate: level 3 is within 10% of level 6's size at a third
 * of its time); a streamed answer's deflate state is about 256 KiB, counted
 * against the memory budget */
#define SRV__GZIP_LEVEL 3
#define SRV__GZIP_STATE (256 * 1024)
/* libmicrohttpd's memory per connection: the request line and headers
 * must fit, and then an answer's headers.  libmicrohttpd clears it for
 * every request, so it is a per-request cost too: with 64 KiB /health
 * answered 40k requests/s, with 32 KiB 57k (wrk, one run). */
#define SRV__CONN_MEMORY (32 * 1024)
/* A header block (with libmicrohttpd's records of its headers) larger than
 * this is answered 413: what is left is kept for the answer's headers. */
#define SRV__HEADER_ROOM (SRV__CONN_MEMORY - 4096)

/* A chunk's size line (its size and extensions) longer than this is
 * answered 413 (wire.c): with the largest header block the daemon takes,
 * libmicrohttpd 0.9.75 holds a line of 4090 bytes, and answers 500 to a
 * longer one. */
#define SRV__CHUNK_LINE 2048
/* The bytes of a header line that wire.c keeps: a Content-Length's value
 * with blanks around it. */
#define SRV__WIRE_KEEP 64

/* Once fewer than --reserved-connections slots are free, a new connection
 * is taken only from an address that holds fewer than this many (a
 * browser opens up to 6 to a host). */
#define SRV__FEW_CONNECTIONS 8

/* Counts by client key, under a lock of their own (tally.c). */
typedef struct srv__tally srv__tally;
srv__tally *srv__tally_new(void); /* NULL when out of memory */
void srv__tally_free(srv__tally *t);
/* Add @a delta to the count of @a key; its new count. */
long srv__tally_add(srv__tally *t, const char *key, long delta);
/* The count of @a key; and when not NULL, into *keys the number of keys
 * whose count is not 0, into *total the sum of all counts. */
long srv__tally_get(srv__tally *t, const char *key, unsigned *keys,
                    long *total);

typedef struct srv__jobs srv__jobs;
typedef struct srv__results srv__results;

/* What wire.c knows of the requests in a connection's bytes. */
typedef struct srv__wire {
  int state;
  int fresh;                       /* no request line yet */
  int lengths, encodings, chunked; /* the block's headers of framing */
  int odd;                         /* a header the framer does not read */
  int in_size, digits;             /* a size line's hex digits */
  int cr;                          /* the line so far ends in CR */
  unsigned long long left;         /* bytes of the body or chunk */
  unsigned long long size;         /* the chunk's, from its size line */
  size_t line, kept;               /* bytes of the line, and kept of it */
  char keep[SRV__WIRE_KEEP];
} srv__wire;

struct srv__req;

/* One TCP connection, from NOTIFY_CONNECTION's start to its close. */
typedef struct srv__conn {
  struct srv__conn *prev, *next;
  int fd;
  double start;        /* of the request being received */
  int receiving;       /* 0 once the current request is wholly received */
  int shut;            /* the monitor closed it */
  int peer_port;       /* of a TCP peer, else 0 */
  int space_in_target; /* the current request's target, as sent */
  /* the request being received or answered (on the I/O thread) */
  struct srv__req *req;
  srv__wire wire;
  /* for diagnosis (srv_connection_watched) */
  atomic_int requests, suspended, resumed;
  char key[SRV_CLIENT_KEY];
} srv__conn;

struct srv_daemon {
  struct MHD_Daemon *mhd;
  srv_config cfg;
  int port;     /* the port it listens on */
  char url[96]; /* http://ADDR:PORT/ as it listens */
  srv_metrics *metrics;
  srv_pool *pool;
  char transport[48];
  atomic_int draining;
  double started;
  pthread_mutex_t mu; /* the connection list */
  srv__conn *conn_list;
  pthread_t monitor;
  atomic_int monitor_stop;
  atomic_ulong conns_started; /* taken up by libmicrohttpd */
  int monitor_running;
  /* request ids: a per-start random seed mixed with a counter */
  unsigned long long rid_seed;
  atomic_ullong rid_next;
  char (*etags)[24]; /* per row: a static answer's validator, or "" */
  srv__tally *held;  /* bytes against the memory budget, by client */
  srv__tally *conns; /* open connections, by peer address */
  srv__jobs *jobs;   /* NULL: --no-jobs */
};

typedef struct srv__batch srv__batch;

/* The job resources (jobs_http.c), by the path of a request. */
enum {
  SRV__JOBS_LIST = 1, /* /jobs */
  SRV__JOBS_ONE,      /* /jobs/{id} */
  SRV__JOBS_RESULTS   /* /jobs/{id}/results */
};

typedef struct srv__req {
  srv_job job; /* first: a job is its request */
  struct srv_daemon *d;
  struct MHD_Connection *c;
  srv__conn *cn;
  size_t ep; /* endpoint index; api_endpoint_count() until routed */
  int is_post;
  int status;
  int done; /* a response was queued */
  int close;
  int answered; /* the pool handed the request back with r->ar */
  char *buf;
  size_t len, cap;
  size_t expect; /* the body's Content-Length, 0 when not told */
  int raw;       /* answered on the socket (srv__send_raw_problem) */
  const char *accept_encoding; /* Accept-Encoding of a 415, or NULL */
  int over_budget; /* the body came while the memory budget was spent */
  long held;       /* bytes of body and answer counted against the budget */
  double t0;
  size_t bytes;                 /* of the answer's body, as sent */
  char rid[SRV_REQUEST_ID + 1]; /* X-Request-Id, given or made */
  const char *etag;             /* a validator for a static answer, or NULL */
  char cors[128];               /* Access-Control-Allow-Origin, or "" */
  char preflight[24];           /* OPTIONS: the methods the path takes */
  int page;        /* GET /problems/<type>: the page of a problem type */
  int vary_accept; /* the answer depends on Accept (Vary: Accept) */
  int gzip;        /* the client accepts gzip */
  int form;        /* the answer's form its Accept asks for (api_negotiate) */
  char method[8];
  char path[96];
  char key[SRV_CLIENT_KEY]; /* the client, for the pool's queues */
  api_response ar;
  api_batch *ab;     /* a POST /batch's items, parsed on a worker */
  srv__batch *batch; /* a POST /batch being answered */
  /* An answer decided on the first call, sent on a later one: libmicrohttpd
   * handles a response queued during the first call of a request far more
   * slowly (about 200 us each, serialised), so only what must stop a body
   * (413, and framing that could smuggle a request) is queued that early. */
  int p_status;
  api_problem_kind p_kind;
  const char *p_allow;
  char p_detail[128];
  /* jobs (jobs_http.c) */
  int async; /* a computing POST with Prefer: respond-async: a job */
  int jobs;  /* a job resource: SRV__JOBS_*, else 0 */
  int wait;  /* GET /jobs/{id}/results: wait for the chunks not stored */
  long limit, offset;               /* GET /jobs: the page */
  char job_id[STORE_ID_LEN + 1];    /* of a job resource */
  char job_path[32];                /* ... and its endpoint */
  char location[16 + STORE_ID_LEN]; /* a 201's Location, or "" */
  srv__results *res;                /* GET /jobs/{id}/results being answered */
  /* a page of the user's guide (docs.c) */
  const char *doc; /* its bytes, embedded; NULL for anything else */
  size_t doc_len;
  const char *doc_ctype;
} srv__req;

/* ---- daemon.c ------------------------------------------------------------ */

double srv__now(void); /* monotonic seconds */

/* What the daemon tells the api about itself while it runs @a job (whose
 * cancel flag the computation polls). */
api_server_info srv__server_info(struct srv_daemon *d, srv_job *job);

/* ---- request.c: libmicrohttpd's callbacks for a request ------------------ */

/* Decide an error answer now (during admission), send it on the next call
 * of the handler. */
enum MHD_Result srv__defer(srv__req *r, api_problem_kind kind,
                           const char *detail, const char *allow);
/* Whether the client holds the representation of @a r's static answer
 * (If-None-Match names r->etag, or its gzip variant when it takes gzip). */
int srv__not_modified(struct MHD_Connection *c, const srv__req *r);
/* Queue @a r's work in the pool (resumed with r->ar), or refuse it. */
enum MHD_Result srv__submit(struct srv_daemon *d, struct MHD_Connection *c,
                            srv__req *r);

/* Whether the peer @a addr (as text) is a --trusted-proxy. */
int srv__trusted(const struct srv_daemon *d, const char *addr);

enum MHD_Result srv__handler(void *cls, struct MHD_Connection *c,
                             const char *url, const char *method,
                             const char *version, const char *upload_data,
                             size_t *upload_data_size, void **con_cls);
/* libmicrohttpd's URI_LOG_CALLBACK: the request line's target, before it is
 * decoded (a space in it, which libmicrohttpd's lenient mode takes, is
 * refused by the handler). */
void *srv__target(void *cls, const char *uri, struct MHD_Connection *c);
void srv__completed(void *cls, struct MHD_Connection *c, void **con_cls,
                    enum MHD_RequestTerminationCode toe);

/* ---- reply.c ------------------------------------------------------------- */

/* Whether Accept-Encoding names gzip with a quality above 0. */
int srv__accepts_gzip(struct MHD_Connection *c);
/* The origin of a browser's request into r->cors, when --cors-origin allows
 * it. */
void srv__cors_of(const struct srv_daemon *d, struct MHD_Connection *c,
                  srv__req *r);
/* The headers every answer carries (X-Request-Id, CORS). */
void srv__common_headers(const srv__req *r, struct MHD_Response *resp);
/* Queue @a body (len bytes, malloc'd; the answer owns it), gzipped when the
 * client takes it; a Retry-After, an Allow and a Connection: close when
 * asked. */
enum MHD_Result srv__send_body(struct MHD_Connection *c, srv__req *r,
                               int status, char *body, size_t len,
                               const char *ctype, int retry_after,
                               const char *allow, int close);
/* Queue an answer of the api (which it takes over), whole or streamed. */
enum MHD_Result srv__send_api(struct MHD_Connection *c, srv__req *r,
                              api_response *ar, const char *allow);
/* Queue a problem of @a kind. */
enum MHD_Result srv__send_problem(struct MHD_Connection *c, srv__req *r,
                                  api_problem_kind kind, const char *detail,
                                  const char *limit, double limit_value,
                                  const char *allow);
/* Write a problem of @a kind straight to the connection's socket and shut
 * its sending side, for when libmicrohttpd cannot queue an answer (a body
 * is being received; a header block has left no room for an answer's
 * headers).  The request is then r->raw: the handler discards what still
 * comes, and closes the connection once the request is in. */
void srv__send_raw_problem(srv__req *r, api_problem_kind kind,
                           const char *detail, const char *limit,
                           double limit_value);
/* Count @a bytes against the memory budget for request @a r (negative to
 * give them back). */
void srv__hold(struct srv_daemon *d, srv__req *r, long bytes);
/* Count @a bytes against the memory budget for the client @a key. */
void srv__held(struct srv_daemon *d, const char *key, long bytes);
/* Whether the client @a key may not start work: 0 when it may, else the
 * budget is spent (1) or the client holds its share of it (2). */
int srv__over_budget(struct srv_daemon *d, const char *key);
/* The 503 for srv__over_budget's refusal of client @a key, into @a ar. */
void srv__budget_problem(struct srv_daemon *d, const char *key,
                         api_response *ar);

/* ---- batch.c ------------------------------------------------------------- */

/* On a worker: parse and check the body of a POST /batch, into r->ab (its
 * bytes held by @a r), or its problem into r->ar. */
void srv__batch_open(srv__req *r);
/* Back on the I/O thread with r->ab: start the answer. */
enum MHD_Result srv__batch_start(struct srv_daemon *d, struct MHD_Connection *c,
                                 srv__req *r);
/* The request of a batch has completed: what is still in the pool stops.
 * Returns the bytes of the answer written. */
size_t srv__batch_detach(srv__batch *b);

/* ---- jobs.c: the engine of jobs ------------------------------------------ */

/* Seconds since the epoch (the store's times: replicas compare them). */
double srv__wall(void);

/* A call to the store, its latency observed: rc = call. */
#define SRV__TIMED(d, rc, call)                                                \
  do {                                                                         \
    double t0_ = srv__now();                                                   \
    rc = (call);                                                               \
    srv_metrics_store((d)->metrics, srv__now() - t0_);                         \
  } while (0)

/* Open the store (a failure is noted for srv__jobs_announce: jobs are
 * then answered 503 until it opens) and start the runners and the ticker.  NULL
 * when out of memory. */
srv__jobs *srv__jobs_start(struct srv_daemon *d);
/* The limits a job is opened and its chunks run under: the daemon's, with
 * --max-job-body and --max-job-items for the body and a /batch's items. */
api_limits srv__job_limits(const struct srv_daemon *d);
/* Log what opening the store at the start had to say (after the line
 * that tells the daemon's URL, which a supervisor reads first). */
void srv__jobs_announce(srv__jobs *js);
/* The runners stop: a chunk computing is cancelled and not stored (its
 * lease lapses), the others are left to the store. */
void srv__jobs_stop(srv__jobs *js);
/* Stop the ticker, close the store, free; NULL-safe. */
void srv__jobs_free(srv__jobs *js);
/* The store, or NULL when it is not open (opening it is tried again, at
 * most every few seconds). */
store *srv__jobs_store(srv__jobs *js);
/* A job was submitted here: wake a runner. */
void srv__jobs_wake(srv__jobs *js);
/* Job @a id was dismissed here: its chunks computing stop at once. */
void srv__jobs_cancel(srv__jobs *js, const char *id);
/* The path a job of endpoint @a ep answering in @a form is stored under
 * (its endpoint's path; "?f=ndjson" after it for API_FORM_NDJSON), into
 * @a path of @a n bytes. */
void srv__job_path(size_t ep, api_form form, char *path, size_t n);
/* A stored job's @a path back into its endpoint and form: 0, or -1 when
 * it names none served here. */
int srv__job_route(const char *path, size_t *ep, api_form *form);
/* Job @a id (of endpoint @a path), opened from its stored body, shared by
 * the few last used (a batch of many chunks is parsed once): the job; or
 * NULL with its problem in @a out (out->status 0: its body is gone, the
 * job dismissed or expired; 503: the store failed). */
api_job *srv__jobs_open(srv__jobs *js, const char *id, const char *path,
                        api_response *out);
/* Done with a job of srv__jobs_open. */
void srv__jobs_release(srv__jobs *js, api_job *j);
/* The connection of a results stream @a res waits for its next chunk: the
 * ticker resumes it (srv__results_resume) within TICK_MS. */
void srv__jobs_wait(srv__jobs *js, srv__results *res);
/* ... no longer: it has completed. */
void srv__jobs_unwait(srv__jobs *js, srv__results *res);
/* The connection of results stream @a res, suspended, needs its next
 * chunk read from the store: the reader thread reads it
 * (srv__results_fetch), in the order asked. */
void srv__jobs_fetch(srv__jobs *js, srv__results *res);
/* The store's counts into the metrics (at most once a second). */
void srv__jobs_metrics(srv__jobs *js);

/* ---- docs.c: the user's guide at /docs/ ---------------------------------- */

/* Admission of a request whose path is the guide's (/docs...): the page
 * into r->doc, or an answer deferred; 0 when the path is not the guide's. */
int srv__docs_admit(srv__req *r, const char *url, const char *method);
/* The last call of a page's request: the page, or 304. */
enum MHD_Result srv__docs_answer(struct MHD_Connection *c, srv__req *r);

/* ---- jobs_http.c: jobs over HTTP ----------------------------------------- */

/* Whether the request's Prefer headers hold respond-async (RFC 7240). */
int srv__prefers_async(struct MHD_Connection *c);
/* Admission of a request whose path is a job resource (/jobs...): its
 * route, id and parameters into @a r, or an answer deferred; 0 when the
 * path is no job resource. */
int srv__jobs_admit(struct srv_daemon *d, struct MHD_Connection *c, srv__req *r,
                    const char *url, const char *method);
/* On a worker: a job resource's work, every call of the store among it (a
 * submission: the job stored; a list, a status, a dismissal: read or
 * written; a results request: the job opened), its answer into r->ar. */
void srv__jobs_run(srv__req *r);
/* Back on the I/O thread: the answer, or the results' stream. */
enum MHD_Result srv__jobs_resumed(struct srv_daemon *d,
                                  struct MHD_Connection *c, srv__req *r);
/* The ticker resumes a results stream that waited. */
void srv__results_resume(srv__results *res);
/* On the reader thread: the next chunk of @a res read from the store, and
 * its connection resumed. */
void srv__results_fetch(srv__results *res);
/* The stream after @a res in the reader's queue (its link). */
srv__results **srv__results_next(srv__results *res);
/* The request of a results stream has completed. */
void srv__results_detach(srv__results *res);

/* ---- monitor.c ----------------------------------------------------------- */

/* libmicrohttpd's ACCEPT_POLICY: whether a new connection from @a addr is
 * taken (--per-ip-connections, --reserved-connections). */
enum MHD_Result srv__accept(void *cls, const struct sockaddr *addr,
                            socklen_t addrlen);
/* libmicrohttpd's NOTIFY_CONNECTION: a connection's start and close. */
void srv__connection(void *cls, struct MHD_Connection *c, void **socket_ctx,
                     enum MHD_ConnectionNotificationCode toe);
/* The monitor thread (started by srv_start, stopped by monitor_stop). */
void *srv__monitor(void *arg);
/* Whether the peer of socket @a fd has closed its end. */
int srv__peer_closed(int fd);
/* A connection's deadline for a request: @a receiving 1 starts it now (the
 * next request on @a cn), 0 stops it (the request is wholly received);
 * @a cn may be NULL. */
void srv__receiving(struct srv_daemon *d, srv__conn *cn, int receiving);

/* ---- wire.c -------------------------------------------------------------- */

/* Follow the bytes libmicrohttpd reads from @a cn (its fd set): 0, or -1
 * when its descriptor is beyond the table. */
int srv__wire_open(srv__conn *cn);
/* Stop following them: before the descriptor is closed. */
void srv__wire_close(srv__conn *cn);
/* Whether socket @a fd's end for reading is the daemon's own, not the
 * client's: a refusal waits for libmicrohttpd's next read (any thread). */
int srv__wire_pending(int fd);

#endif
