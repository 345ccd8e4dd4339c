/*
 * daemon.c: HTTP with libmicrohttpd: routing, bodies, admission, the
 * compute pool's requests, the watch over clients, logging.
 *
 * Sockets.  One internal polling thread with epoll
 * (MHD_USE_EPOLL_INTERNAL_THREAD): an idle or slow connection costs a
 * socket, not a thread.  What needs no computing (the api's inline
 * endpoints, and every refusal) is answered on that thread at once.
 *
 * Compute.  A request that computes is suspended once its body is in
 * (MHD_suspend_connection), handed to the pool (pool.c: per-client queues,
 * round robin, a bounded queue per client, at most client_workers running
 * per client), and resumed with its answer by the worker that computed it.
 *
 * Watch.  While a connection is suspended libmicrohttpd does not look at
 * its socket, so a monitor thread does, every MONITOR_MS: a peer that has
 * closed its end has its waiting work dropped and its running work flagged
 * (the core polls the flag).  The monitor also closes connections that do
 * not deliver a whole request (headers and body) within request_timeout of
 * their start or of the end of their previous request: libmicrohttpd's own
 * timeout counts idle time only, which a byte every few seconds resets.
 *
 * Framing that could smuggle a request (two Content-Length headers,
 * Content-Length with Transfer-Encoding, two Host headers) is refused with
 * 400 and the connection is closed.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <microhttpd.h>
#include <zlib.h>

#include "server.h"

#define MONITOR_MS 20
/* libmicrohttpd's memory per connection: the request line and headers
 * must fit (a larger block is answered 431).  libmicrohttpd clears it for
 * every request, so it is a per-request cost too: with 64 KiB /health
 * answered 40k requests/s, with 32 KiB 57k (wrk, one run). */
#define CONN_MEMORY (32 * 1024)
#define STREAM_CHUNK (32 * 1024) /* bytes of a streamed answer at a time */
/* gzip for a client that accepts it: answers from this size on (smaller ones
 * gain too little for the work), at a level that keeps it cheap next to the
 * computation (a 2000-sample /simulate: level 3 is within 10% of level 6's
 * size at a third of its time); a streamed answer's deflate state is about
 * 256 KiB, counted against the memory budget */
#define GZIP_MIN 1024
#define GZIP_LEVEL 3
#define GZIP_STATE (256 * 1024)

/* One TCP connection, from NOTIFY_CONNECTION's start to its close. */
typedef struct conn {
  struct conn *prev, *next;
  int fd;
  double start;  /* of the request being received */
  int receiving; /* 0 once the current request is wholly received */
  int shut;      /* the monitor closed it */
  int peer_port; /* of a TCP peer, else 0 */
  /* for diagnosis (srv_connection_watched) */
  atomic_int requests, suspended, resumed;
  char key[SRV_CLIENT_KEY];
} conn;

struct srv_daemon {
  struct MHD_Daemon *mhd;
  srv_config cfg;
  int port; /* the port it listens on */
  srv_metrics *metrics;
  srv_pool *pool;
  char transport[48];
  atomic_int draining;
  double started;
  pthread_mutex_t mu; /* the connection list */
  conn *conns;
  pthread_t monitor;
  atomic_int monitor_stop;
  atomic_ulong conns_started; /* taken up by libmicrohttpd */
  int monitor_running;
  /* request ids: a per-start random seed mixed with a counter */
  unsigned long long rid_seed;
  atomic_ullong rid_next;
  char (*etags)[24]; /* per row: a static answer's validator, or "" */
};

enum { R_FRESH = 0, R_ANSWERED = 1 };

typedef struct req {
  srv_job job; /* first: a job is its request */
  struct srv_daemon *d;
  struct MHD_Connection *c;
  conn *cn;
  size_t ep; /* endpoint index; api_endpoint_count() until routed */
  int is_post;
  int status;
  int done; /* a response was queued */
  int close;
  int answered; /* the pool handed the request back with r->ar */
  char *buf;
  size_t len, cap;
  int too_big;
  int over_budget; /* the body came while the memory budget was spent */
  long held;       /* bytes of body and answer counted against the budget */
  double t0;
  size_t bytes;                 /* of the answer's body, as sent */
  char rid[SRV_REQUEST_ID + 1]; /* X-Request-Id, given or made */
  const char *etag;             /* a validator for a static answer, or NULL */
  char cors[128];               /* Access-Control-Allow-Origin, or "" */
  char preflight[24];           /* OPTIONS: the methods the path takes */
  int gzip;                     /* the client accepts gzip */
  char method[8];
  char path[96];
  char key[SRV_CLIENT_KEY]; /* the client, for the pool's queues */
  api_response ar;
  struct batch *batch; /* a POST /batch being answered */
  /* An answer decided on the first call, sent on a later one: libmicrohttpd
   * handles a response queued during the first call of a request far more
   * slowly (about 200 us each, serialised), so only what must stop a body
   * (413, and framing that could smuggle a request) is queued that early. */
  int p_status;
  api_problem_kind p_kind;
  const char *p_allow;
  char p_detail[128];
} req;

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Whether Accept-Encoding names gzip with a quality above 0. */
static int accepts_gzip(struct MHD_Connection *c) {
  const char *ae =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Accept-Encoding");
  for (const char *p = ae ? strcasestr(ae, "gzip") : NULL; p;
       p = strcasestr(p + 4, "gzip")) {
    const char *e = p + 4;
    while (*e == ' ' || *e == '\t')
      e++;
    if ((p != ae && p[-1] != ',' && p[-1] != ' ' && p[-1] != '\t') ||
        (*e && *e != ',' && *e != ';'))
      continue; /* part of another token */
    if (*e != ';')
      return 1;
    const char *q = strcasestr(e, "q=");
    const char *next = strchr(e, ',');
    return !q || (next && q > next) || strtod(q + 2, NULL) > 0;
  }
  return 0;
}

/* A media type worth compressing: the api's JSON, NDJSON and problems. */
static int compressible(const char *ctype) {
  return ctype && (!strncmp(ctype, "application/json", 16) ||
                   !strncmp(ctype, "application/x-ndjson", 20) ||
                   !strncmp(ctype, "application/problem+json", 24) ||
                   !strncmp(ctype, "text/", 5));
}

/* @a body (len bytes) gzipped into a new buffer (*out, *out_len); -1 when
 * out of memory. */
static int gzip_buffer(const char *body, size_t len, char **out,
                       size_t *out_len) {
  z_stream zs;
  memset(&zs, 0, sizeof zs);
  if (deflateInit2(&zs, GZIP_LEVEL, Z_DEFLATED, 15 + 16, 8,
                   Z_DEFAULT_STRATEGY) != Z_OK)
    return -1;
  size_t cap = deflateBound(&zs, (uLong)len);
  char *b = malloc(cap);
  if (!b) {
    deflateEnd(&zs);
    return -1;
  }
  zs.next_in = (Bytef *)(uintptr_t)body;
  zs.avail_in = (uInt)len;
  zs.next_out = (Bytef *)b;
  zs.avail_out = (uInt)cap;
  int rc = deflate(&zs, Z_FINISH);
  *out_len = cap - zs.avail_out;
  deflateEnd(&zs);
  if (rc != Z_STREAM_END) {
    free(b);
    return -1;
  }
  *out = b;
  return 0;
}

/* The headers every answer carries: nosniff, the request id, and for a
 * page of an allowed origin (--cors-origin) what its browser needs: the
 * origin allowed, the headers it may read, and on a preflight the methods
 * and request headers it may use, for 10 minutes. */
static void common_headers(const req *r, struct MHD_Response *resp) {
  MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
  if (r->rid[0])
    MHD_add_response_header(resp, "X-Request-Id", r->rid);
  if (!r->d || !r->d->cfg.n_origins)
    return;
  MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, "Origin");
  if (!r->cors[0])
    return;
  MHD_add_response_header(resp, "Access-Control-Allow-Origin", r->cors);
  if (r->preflight[0]) {
    MHD_add_response_header(resp, "Access-Control-Allow-Methods", r->preflight);
    MHD_add_response_header(resp, "Access-Control-Allow-Headers",
                            "Content-Type, X-Request-Id");
    MHD_add_response_header(resp, "Access-Control-Max-Age", "600");
  } else {
    MHD_add_response_header(resp, "Access-Control-Expose-Headers",
                            "X-Request-Id, Retry-After, ETag");
  }
}

/* The origin of a browser's request, when --cors-origin allows it. */
static void cors_of(const struct srv_daemon *d, struct MHD_Connection *c,
                    req *r) {
  const char *o = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Origin");
  r->cors[0] = 0;
  if (!o || !d->cfg.n_origins)
    return;
  for (int i = 0; i < d->cfg.n_origins; i++) {
    if (!strcmp(d->cfg.origins[i], "*")) {
      snprintf(r->cors, sizeof r->cors, "*");
      return;
    }
    if (!strcasecmp(d->cfg.origins[i], o)) {
      snprintf(r->cors, sizeof r->cors, "%s", d->cfg.origins[i]);
      return;
    }
  }
}

static enum MHD_Result send_body(struct MHD_Connection *c, req *r, int status,
                                 char *body, size_t len, const char *ctype,
                                 int retry_after, const char *allow,
                                 int close) {
  int gz = 0;
  if (r->gzip && status != 304 && len >= GZIP_MIN && compressible(ctype) &&
      len < (1UL << 31)) {
    char *z;
    size_t zlen;
    if (gzip_buffer(body, len, &z, &zlen) == 0) {
      free(body);
      body = z;
      len = zlen;
      gz = 1;
    }
  }
  struct MHD_Response *resp =
      MHD_create_response_from_buffer(len, body, MHD_RESPMEM_MUST_FREE);
  enum MHD_Result ok;
  if (!resp) {
    free(body);
    return MHD_NO;
  }
  if (ctype)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
  if (compressible(ctype))
    MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, "Accept-Encoding");
  if (gz)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_ENCODING, "gzip");
  common_headers(r, resp);
  if (ctype && !strncmp(ctype, "text/html", 9))
    /* the explorer: its own files only, and calls to any daemon it is
     * pointed at */
    MHD_add_response_header(resp, "Content-Security-Policy",
                            "default-src 'self'; connect-src 'self' http: "
                            "https:; img-src 'self' data:; base-uri 'none'; "
                            "form-action 'none'; frame-ancestors 'none'");
  if (r->etag) {
    /* the gzipped representation has its own validator */
    char tag[40];
    snprintf(tag, sizeof tag, "%.*s%s\"", (int)strlen(r->etag) - 1, r->etag,
             gz || (status == 304 && r->gzip) ? "-gzip" : "");
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ETAG, tag);
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CACHE_CONTROL,
                            "public, max-age=300");
  }
  if (retry_after)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_RETRY_AFTER, "1");
  if (allow)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ALLOW, allow);
  if (close)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONNECTION, "close");
  ok = MHD_queue_response(c, (unsigned)status, resp);
  MHD_destroy_response(resp);
  r->status = status;
  r->bytes = len;
  r->done = 1;
  return ok;
}

/* Count @a bytes against the memory budget for request @a r (negative to
 * give them back). */
static void hold(struct srv_daemon *d, req *r, long bytes) {
  r->held += bytes;
  srv_metrics_held(d->metrics, bytes);
}

static int over_budget(const struct srv_daemon *d) {
  return srv_metrics_held(d->metrics, 0) >= (long)d->cfg.memory_mb << 20;
}

/* A streamed answer and the request it answers, whose byte count it keeps
 * (libmicrohttpd reads the stream only while the request is in progress;
 * it may free it after the request has completed). */
typedef struct sstream {
  api_stream *s;
  req *r;
  /* gzip: the deflate state and the answer's text not yet deflated */
  int gz, eof, end;
  z_stream zs;
  char in[STREAM_CHUNK];
} sstream;

/* The next gzipped bytes of the stream: deflate what the answer gives until
 * some output comes, or the end. */
static ssize_t gz_read(sstream *st, char *buf, size_t max) {
  z_stream *zs = &st->zs;
  zs->next_out = (Bytef *)buf;
  zs->avail_out = (uInt)max;
  while (zs->avail_out == max && !st->end) {
    if (zs->avail_in == 0 && !st->eof) {
      long n = api_stream_read(st->s, st->in, sizeof st->in);
      if (n < 0)
        return MHD_CONTENT_READER_END_WITH_ERROR;
      st->eof = n == 0;
      zs->next_in = (Bytef *)st->in;
      zs->avail_in = (uInt)n;
    }
    int rc = deflate(zs, st->eof ? Z_FINISH : Z_NO_FLUSH);
    if (rc == Z_STREAM_END)
      st->end = 1;
    else if (rc != Z_OK && rc != Z_BUF_ERROR)
      return MHD_CONTENT_READER_END_WITH_ERROR;
  }
  size_t got = max - zs->avail_out;
  return got ? (ssize_t)got : MHD_CONTENT_READER_END_OF_STREAM;
}

static ssize_t stream_read(void *cls, uint64_t pos, char *buf, size_t max) {
  sstream *st = cls;
  (void)pos;
  if (st->gz) {
    ssize_t n = gz_read(st, buf, max);
    if (n > 0)
      st->r->bytes += (size_t)n;
    return n;
  }
  long n = api_stream_read(st->s, buf, max);
  if (n > 0)
    st->r->bytes += (size_t)n;
  return n < 0   ? MHD_CONTENT_READER_END_WITH_ERROR
         : n > 0 ? (ssize_t)n
                 : MHD_CONTENT_READER_END_OF_STREAM;
}

static void stream_free(void *cls) {
  sstream *st = cls;
  if (st->gz)
    deflateEnd(&st->zs);
  api_stream_free(st->s);
  free(st);
}

/* A large answer, written a chunk at a time as the client reads it. */
static enum MHD_Result send_stream(struct MHD_Connection *c, req *r,
                                   api_response *ar) {
  sstream *st = calloc(1, sizeof *st);
  if (st && r->gzip && compressible(ar->content_type) &&
      deflateInit2(&st->zs, GZIP_LEVEL, Z_DEFLATED, 15 + 16, 8,
                   Z_DEFAULT_STRATEGY) == Z_OK) {
    st->gz = 1;
    if (r->d)
      hold(r->d, r, GZIP_STATE);
  }
  struct MHD_Response *resp =
      st ? MHD_create_response_from_callback(MHD_SIZE_UNKNOWN, STREAM_CHUNK,
                                             stream_read, st, stream_free)
         : NULL;
  enum MHD_Result ok;
  if (!resp) {
    if (st && st->gz)
      deflateEnd(&st->zs);
    free(st);
    api_response_free(ar);
    return MHD_NO;
  }
  st->s = ar->stream;
  st->r = r;
  ar->stream = NULL; /* the response owns it now */
  MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ar->content_type);
  if (compressible(ar->content_type))
    MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, "Accept-Encoding");
  if (st->gz)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_ENCODING, "gzip");
  common_headers(r, resp);
  ok = MHD_queue_response(c, (unsigned)ar->status, resp);
  MHD_destroy_response(resp);
  r->status = ar->status;
  r->done = 1;
  return ok;
}

/* An answer of the api: a 503 always says when to come back, and a 413,
 * a 503 or a refused framing closes the connection.  What the answer holds
 * counts against the memory budget until the request completes. */
/* A problem's body with the request's id as a member "request_id" (an
 * extension member of RFC 9457), so that a client's report of it can be
 * found in the log. */
static void problem_with_id(const req *r, api_response *ar) {
  if (!r->rid[0] || !ar->body || ar->len < 2 || ar->body[0] != '{' ||
      strcmp(ar->content_type, "application/problem+json") != 0)
    return;
  size_t n = ar->len + strlen(r->rid) + 20;
  char *b = malloc(n);
  if (!b)
    return;
  int k = snprintf(b, n, "{\"request_id\":\"%s\",%s", r->rid, ar->body + 1);
  if (k < 0 || (size_t)k >= n) {
    free(b);
    return;
  }
  free(ar->body);
  ar->body = b;
  ar->held += (size_t)k - ar->len;
  ar->len = (size_t)k;
}

static enum MHD_Result send_api(struct MHD_Connection *c, req *r,
                                api_response *ar, const char *allow) {
  int busy = ar->status == 503;
  problem_with_id(r, ar);
  if (r->d)
    hold(r->d, r, (long)ar->held);
  if (ar->stream)
    return send_stream(c, r, ar);
  enum MHD_Result ok =
      send_body(c, r, ar->status, ar->body, ar->len, ar->content_type, busy,
                allow, busy || ar->status == 413 || r->close);
  ar->body = NULL;
  return ok;
}

static enum MHD_Result send_problem(struct MHD_Connection *c, req *r,
                                    api_problem_kind kind, const char *detail,
                                    const char *limit, double limit_value,
                                    const char *allow) {
  api_response ar;
  api_problem(&ar, kind, detail, NULL, limit, limit_value);
  return send_api(c, r, &ar, allow);
}

static char *metrics_text(void *cls) {
  return srv_metrics_render(((struct srv_daemon *)cls)->metrics);
}

static int job_cancelled(void *cls) {
  return atomic_load(&((srv_job *)cls)->cancel);
}

/* What the daemon tells the api about itself while it runs @a job (whose
 * cancel flag the computation polls). */
static api_server_info server_info(struct srv_daemon *d, srv_job *job) {
  api_server_info info = {now() - d->started,
                          srv_metrics_in_flight(d->metrics, 0),
                          d->transport,
                          metrics_text,
                          d,
                          job_cancelled,
                          job,
                          d->cfg.stream_above};
  return info;
}

/* One request to the api, with what the daemon knows of itself. */
static void handle(struct srv_daemon *d, req *r, api_response *ar) {
  api_server_info info = server_info(d, &r->job);
  api_handle(r->ep, r->buf ? r->buf : "", r->len, &d->cfg.lim, &info, ar);
  if (ar->status >= 500 && ar->status != 503)
    fprintf(stderr, "stickslipd: %s %s answered %d: %.200s\n", r->method,
            r->path, ar->status, ar->body ? ar->body : "");
}

/* ---- the pool's side of a request ---------------------------------------- */

static void budget_problem(struct srv_daemon *d, api_response *ar) {
  char detail[160];
  srv_metrics_over_budget(d->metrics);
  snprintf(detail, sizeof detail,
           "the answers in flight hold %.1f MiB, the memory budget is %zu "
           "MiB; retry after a second",
           (double)srv_metrics_held(d->metrics, 0) / 1048576.0,
           d->cfg.memory_mb);
  api_problem(ar, API_P_OVERLOADED, detail, NULL, NULL, 0);
}

static void job_queued(srv_job *j) {
  req *r = (req *)j;
  if (r->cn)
    atomic_fetch_add(&r->cn->suspended, 1);
  MHD_suspend_connection(r->c);
}

/* Whether the peer of socket @a fd has closed its end: a read that finds
 * the end of the stream (or a reset) says so; pending bytes (a pipelined
 * request) or nothing to read say it is still there. */
static int fd_closed(int fd) {
  char b;
  if (fd < 0)
    return 0;
  ssize_t k = recv(fd, &b, 1, MSG_PEEK | MSG_DONTWAIT);
  return k == 0 ||
         (k < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
}

/* Has the client of a suspended request gone away?  While a connection is
 * suspended libmicrohttpd does not look at its socket, so the monitor asks
 * here. */
static int job_gone(srv_job *j) {
  req *r = (req *)j;
  return r->cn && fd_closed(r->cn->fd);
}

/* The memory budget is checked again when the work starts: what was
 * queued while it was free may find it spent. */
static void job_run(srv_job *j) {
  req *r = (req *)j;
  if (over_budget(r->d))
    budget_problem(r->d, &r->ar);
  else
    handle(r->d, r, &r->ar);
  /* the answer counts from now on, not from when it is sent */
  hold(r->d, r, (long)r->ar.held);
  r->ar.held = 0;
  /* the body is no longer needed: give its bytes back now */
  free(r->buf);
  r->buf = NULL;
  hold(r->d, r, -(long)r->len);
  r->len = r->cap = 0;
}

/* Back to the I/O thread with an answer: the pool is done with the job. */
static void job_done(srv_job *j) {
  req *r = (req *)j;
  if (j->state == SRV_JOB_CANCELLED) {
    api_response_free(&r->ar);
    api_problem(&r->ar, API_P_CLIENT_CLOSED, "the client went away", NULL, NULL,
                0);
    srv_metrics_cancelled(r->d->metrics);
  } else if (j->state == SRV_JOB_REFUSED) {
    api_problem(&r->ar, API_P_SHUTTING_DOWN,
                "the server is shutting down; retry on another replica or "
                "later",
                NULL, NULL, 0);
  }
  r->answered = 1;
  if (r->cn)
    atomic_fetch_add(&r->cn->resumed, 1);
  MHD_resume_connection(r->c);
}

static const srv_job_ops REQUEST_JOB = {job_queued, job_run, job_done,
                                        job_gone};

/* Queue the computation, or refuse it at once. */
static enum MHD_Result submit(struct srv_daemon *d, struct MHD_Connection *c,
                              req *r) {
  r->job.ops = &REQUEST_JOB;
  int rc = srv_pool_submit(d->pool, &r->job, r->key);
  if (rc == 0)
    return MHD_YES; /* suspended by job_queued; resumed by job_done */
  if (rc == SRV_POOL_FULL) {
    char detail[128];
    srv_metrics_busy(d->metrics);
    snprintf(detail, sizeof detail,
             "this client already has %u computations waiting; retry after "
             "a second",
             d->cfg.client_queue);
    return send_problem(c, r, API_P_OVERLOADED, detail, NULL, 0, NULL);
  }
  return send_problem(
      c, r, rc == SRV_POOL_NOMEM ? API_P_OUT_OF_MEMORY : API_P_SHUTTING_DOWN,
      "the computation could not be queued", NULL, 0, NULL);
}

/* ---- POST /batch ---------------------------------------------------------
 *
 * A batch's answer is one chunked response whose lines are written as its
 * items are done.  Its items are jobs of the pool like any request, in the
 * queue of the batch's client; at most batch_parallel of them are in flight
 * (queued, running, or done with a line not yet wholly written), so a
 * batch holds at most that many answers, and its client's other requests
 * still get their turn.  When no line is ready the response's reader
 * suspends the connection, and the next item done resumes it.  When the
 * client goes away the items that wait are dropped and the one that runs
 * is told to stop, as for any request.
 */

typedef struct bitem {
  srv_job job; /* first: a job is its item */
  struct batch *b;
  size_t i;
  api_response ar;
  struct bitem *next; /* in the batch's list of items done */
} bitem;

typedef struct batch {
  pthread_mutex_t mu;
  struct srv_daemon *d;
  struct MHD_Connection *c; /* NULL once the request has completed */
  api_batch *ab;
  char key[SRV_CLIENT_KEY];
  atomic_int fd;   /* of the connection; -1 once it has completed */
  atomic_int gone; /* the client went away: no more items */
  size_t n, next;  /* items, and the next one to send to the pool */
  size_t in_flight, in_pool;
  size_t ok, failed;
  bitem *ready, *ready_tail; /* done, in the order they were done */
  api_stream *line;          /* the line being written */
  long line_held;
  char *last; /* the last line, once every item's line is written */
  size_t last_len, last_off;
  int waiting; /* the connection is suspended until a line is ready */
  int refs;    /* the response, and each item in the pool */
  long held;   /* bytes counted against the memory budget */
  double t0;
  size_t sent; /* bytes of the answer written */
  /* gzip: each piece of lines deflated with a sync flush, so that the
   * client can read each line as soon as it is written */
  int gz, gz_finishing, gz_end;
  z_stream zs;
  char *gz_in;
} batch;

static void batch_hold(batch *b, long bytes) {
  b->held += bytes;
  srv_metrics_held(b->d->metrics, bytes);
}

static void batch_free(batch *b) {
  if (b->gz)
    deflateEnd(&b->zs);
  free(b->gz_in);
  while (b->ready) {
    bitem *it = b->ready;
    b->ready = it->next;
    api_response_free(&it->ar);
    free(it);
  }
  api_stream_free(b->line);
  free(b->last);
  api_batch_free(b->ab);
  srv_metrics_held(b->d->metrics, -b->held);
  pthread_mutex_destroy(&b->mu);
  free(b);
}

static int batch_gone(batch *b) {
  return atomic_load(&b->gone) || fd_closed(atomic_load(&b->fd));
}

static int item_gone(srv_job *j) { return batch_gone(((bitem *)j)->b); }

/* An item's answer is in: to the list of lines to write (under b->mu). */
static void item_ready(batch *b, bitem *it) {
  it->next = NULL;
  if (b->ready_tail)
    b->ready_tail->next = it;
  else
    b->ready = it;
  b->ready_tail = it;
}

static void item_run(srv_job *j) {
  bitem *it = (bitem *)j;
  batch *b = it->b;
  struct srv_daemon *d = b->d;
  if (over_budget(d)) {
    budget_problem(d, &it->ar);
  } else {
    api_server_info info = server_info(d, &it->job);
    api_batch_run(b->ab, it->i, &d->cfg.lim, &info, &it->ar);
  }
  pthread_mutex_lock(&b->mu);
  batch_hold(b, (long)it->ar.held);
  pthread_mutex_unlock(&b->mu);
}

static void dispatch(batch *b);

static void item_done(srv_job *j) {
  bitem *it = (bitem *)j;
  batch *b = it->b;
  pthread_mutex_lock(&b->mu);
  b->in_pool--;
  b->refs--;
  if (j->state == SRV_JOB_CANCELLED && batch_gone(b)) {
    atomic_store(&b->gone, 1);
    srv_metrics_cancelled(b->d->metrics);
    batch_hold(b, -(long)it->ar.held);
    api_response_free(&it->ar);
    free(it);
    b->in_flight--;
  } else {
    if (j->state == SRV_JOB_REFUSED)
      api_problem(&it->ar, API_P_SHUTTING_DOWN,
                  "the server is shutting down; retry on another replica or "
                  "later",
                  NULL, NULL, 0);
    item_ready(b, it);
    dispatch(b);
  }
  if (b->waiting && b->c) {
    b->waiting = 0;
    MHD_resume_connection(b->c);
  }
  int last = b->refs == 0;
  pthread_mutex_unlock(&b->mu);
  if (last)
    batch_free(b);
}

static const srv_job_ops ITEM_JOB = {NULL, item_run, item_done, item_gone};

/* An item answered at once, without the pool (under b->mu). */
static void item_now(batch *b, bitem *it, api_problem_kind kind,
                     const char *detail) {
  api_problem(&it->ar, kind, detail, NULL, NULL, 0);
  item_ready(b, it);
}

/* Send items to the pool while fewer than batch_parallel are in flight
 * (under b->mu).  When the client's queue is full or the memory budget is
 * spent, wait for an item in flight to finish; with none in flight, the
 * item is answered 503 as a request would be. */
static void dispatch(batch *b) {
  struct srv_daemon *d = b->d;
  while (!atomic_load(&b->gone) && b->next < b->n &&
         b->in_flight < d->cfg.batch_parallel) {
    bitem *it = calloc(1, sizeof *it);
    if (!it)
      return; /* a line written or an item done will try again */
    it->b = b;
    it->i = b->next;
    it->job.ops = &ITEM_JOB;
    int rc;
    if (atomic_load(&d->draining)) {
      item_now(b, it, API_P_SHUTTING_DOWN, "the server is shutting down");
    } else if (over_budget(d)) {
      if (b->in_flight > 0) {
        free(it);
        return;
      }
      budget_problem(d, &it->ar);
      item_ready(b, it);
    } else if ((rc = srv_pool_submit(d->pool, &it->job, b->key)) != 0) {
      if (rc == SRV_POOL_FULL && b->in_flight > 0) {
        free(it);
        return;
      }
      if (rc == SRV_POOL_FULL)
        srv_metrics_busy(d->metrics);
      item_now(b, it,
               rc == SRV_POOL_FULL    ? API_P_OVERLOADED
               : rc == SRV_POOL_NOMEM ? API_P_OUT_OF_MEMORY
                                      : API_P_SHUTTING_DOWN,
               rc == SRV_POOL_FULL ? "this client's queue is full; retry "
                                     "the item after a second"
                                   : "the item could not be queued");
    } else {
      b->in_pool++;
      b->refs++;
    }
    b->next++;
    b->in_flight++;
  }
}

/* The next line to write, into b->line or b->last (under b->mu); 0 when
 * there is none yet, -1 when out of memory. */
static int next_line(batch *b) {
  if (b->ready) {
    bitem *it = b->ready;
    if (!(b->ready = it->next))
      b->ready_tail = NULL;
    if (it->ar.status == 200)
      b->ok++;
    else
      b->failed++;
    size_t held;
    long answer = (long)it->ar.held;
    b->line = api_batch_line(b->ab, it->i, &it->ar, &held);
    free(it);
    batch_hold(b, (long)held - answer);
    b->line_held = (long)held;
    return b->line ? 1 : -1;
  }
  if (b->next == b->n && b->in_flight == 0 && !b->last) {
    api_response done;
    api_batch_done(b->ok, b->failed, now() - b->t0, &done);
    b->last = done.body;
    b->last_len = done.len;
    return b->last ? 1 : -1;
  }
  return 0;
}

/* The reader of a batch's response, on the I/O thread. */
static ssize_t batch_read(void *cls, uint64_t pos, char *buf, size_t max) {
  batch *b = cls;
  size_t got = 0;
  (void)pos;
  pthread_mutex_lock(&b->mu);
  if (atomic_load(&b->gone)) {
    pthread_mutex_unlock(&b->mu);
    return MHD_CONTENT_READER_END_WITH_ERROR;
  }
  while (got < max) {
    if (b->line) {
      long k = api_stream_read(b->line, buf + got, max - got);
      if (k < 0)
        break;
      got += (size_t)k;
      if (got == max)
        break; /* the line may go on */
      api_stream_free(b->line);
      b->line = NULL;
      batch_hold(b, -b->line_held);
      b->in_flight--;
      continue;
    }
    if (b->last) {
      size_t k = b->last_len - b->last_off;
      k = k < max - got ? k : max - got;
      memcpy(buf + got, b->last + b->last_off, k);
      b->last_off += k;
      got += k;
      break;
    }
    dispatch(b);
    int rc = next_line(b);
    if (rc < 0) {
      pthread_mutex_unlock(&b->mu);
      return MHD_CONTENT_READER_END_WITH_ERROR;
    }
    if (rc == 0)
      break;
  }
  ssize_t ret = (ssize_t)got;
  b->sent += got;
  if (got == 0 && b->last)
    ret = MHD_CONTENT_READER_END_OF_STREAM;
  else if (got == 0) {
    /* nothing to write until an item is done: item_done resumes */
    b->waiting = 1;
    MHD_suspend_connection(b->c);
  }
  pthread_mutex_unlock(&b->mu);
  return ret;
}

/* batch_read, gzipped: a piece of lines is deflated with Z_SYNC_FLUSH (its
 * bytes complete for the client at once); output that does not fit is kept
 * by zlib and given first on the next call. */
static ssize_t batch_read_gz(batch *b, uint64_t pos, char *buf, size_t max) {
  z_stream *zs = &b->zs;
  unsigned pend = 0;
  int bits = 0;
  zs->next_out = (Bytef *)buf;
  zs->avail_out = (uInt)max;
  deflatePending(zs, &pend, &bits);
  if (pend == 0 && !b->gz_finishing) {
    size_t in_max = max / 2 < STREAM_CHUNK ? max / 2 : STREAM_CHUNK;
    ssize_t n = batch_read(b, pos, b->gz_in, in_max > 0 ? in_max : 1);
    if (n == MHD_CONTENT_READER_END_WITH_ERROR)
      return n;
    if (n == MHD_CONTENT_READER_END_OF_STREAM)
      b->gz_finishing = 1;
    else if (n == 0)
      return 0; /* nothing ready: batch_read suspended the connection */
    else {
      zs->next_in = (Bytef *)b->gz_in;
      zs->avail_in = (uInt)n;
      b->sent -= (size_t)n; /* counted below as sent, compressed */
    }
  }
  if (b->gz_end)
    return MHD_CONTENT_READER_END_OF_STREAM;
  int rc = deflate(zs, b->gz_finishing ? Z_FINISH : Z_SYNC_FLUSH);
  if (rc == Z_STREAM_END)
    b->gz_end = 1;
  else if (rc != Z_OK && rc != Z_BUF_ERROR)
    return MHD_CONTENT_READER_END_WITH_ERROR;
  size_t got = max - zs->avail_out;
  b->sent += got;
  return got ? (ssize_t)got : MHD_CONTENT_READER_END_OF_STREAM;
}

static ssize_t batch_reader(void *cls, uint64_t pos, char *buf, size_t max) {
  batch *b = cls;
  return b->gz ? batch_read_gz(b, pos, buf, max) : batch_read(b, pos, buf, max);
}

/* The response is done with the batch. */
static void batch_release(void *cls) {
  batch *b = cls;
  pthread_mutex_lock(&b->mu);
  int last = --b->refs == 0;
  pthread_mutex_unlock(&b->mu);
  if (last)
    batch_free(b);
}

/* The request of a batch has completed (answered, or its client gone):
 * what is still in the pool stops, and nothing more is sent there. */
static void batch_detach(batch *b) {
  pthread_mutex_lock(&b->mu);
  atomic_store(&b->gone, 1);
  atomic_store(&b->fd, -1);
  b->c = NULL;
  pthread_mutex_unlock(&b->mu);
}

/* The body of a POST /batch is in (and the daemon takes computations): check
 * it, and start the answer. */
static enum MHD_Result batch_start(struct srv_daemon *d,
                                   struct MHD_Connection *c, req *r) {
  api_response ar;
  api_batch *ab;
  if (api_batch_open(r->buf, r->len, &d->cfg.lim, &ab, &ar) != 0)
    return send_api(c, r, &ar, NULL);
  batch *b = calloc(1, sizeof *b);
  if (!b) {
    api_batch_free(ab);
    return send_problem(c, r, API_P_OUT_OF_MEMORY, "out of memory", NULL, 0,
                        NULL);
  }
  pthread_mutex_init(&b->mu, NULL);
  b->d = d;
  b->c = c;
  b->ab = ab;
  b->n = api_batch_size(ab);
  snprintf(b->key, sizeof b->key, "%s", r->key);
  atomic_store(&b->fd, r->cn ? r->cn->fd : -1);
  b->refs = 1; /* the response */
  b->t0 = r->t0;
  if (r->gzip && (b->gz_in = malloc(STREAM_CHUNK)) &&
      deflateInit2(&b->zs, GZIP_LEVEL, Z_DEFLATED, 15 + 16, 8,
                   Z_DEFAULT_STRATEGY) == Z_OK) {
    b->gz = 1;
    batch_hold(b, GZIP_STATE);
  }
  batch_hold(b, (long)api_batch_held(ab));
  /* the items keep their own copies of their bodies */
  free(r->buf);
  r->buf = NULL;
  hold(d, r, -(long)r->len);
  r->len = r->cap = 0;
  struct MHD_Response *resp = MHD_create_response_from_callback(
      MHD_SIZE_UNKNOWN, STREAM_CHUNK, batch_reader, b, batch_release);
  if (!resp) {
    batch_free(b);
    return MHD_NO;
  }
  MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE,
                          "application/x-ndjson");
  MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, "Accept-Encoding");
  if (b->gz)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_ENCODING, "gzip");
  common_headers(r, resp);
  r->batch = b;
  pthread_mutex_lock(&b->mu);
  dispatch(b);
  pthread_mutex_unlock(&b->mu);
  enum MHD_Result ok = MHD_queue_response(c, MHD_HTTP_OK, resp);
  MHD_destroy_response(resp);
  r->status = MHD_HTTP_OK;
  r->done = 1;
  return ok;
}

/* ---- headers ------------------------------------------------------------- */

int srv_address_text(const char *s, char *out, size_t n) {
  unsigned char ip[16];
  int af = inet_pton(AF_INET, s, ip) == 1    ? AF_INET
           : inet_pton(AF_INET6, s, ip) == 1 ? AF_INET6
                                             : 0;
  return af && inet_ntop(af, ip, out, (socklen_t)n) ? 0 : -1;
}

/* The client of a request: the peer's address, or, when the peer is a
 * trusted proxy, the first address of X-Forwarded-For (the one the first
 * proxy saw), if it is an address. */
static void client_of(const struct srv_daemon *d, struct MHD_Connection *c,
                      req *r) {
  const char *peer = r->cn ? r->cn->key : "?";
  snprintf(r->key, sizeof r->key, "%s", peer);
  int trusted = 0;
  for (int i = 0; i < d->cfg.n_trusted && !trusted; i++)
    trusted = strcmp(peer, d->cfg.trusted[i]) == 0;
  const char *xff = trusted ? MHD_lookup_connection_value(c, MHD_HEADER_KIND,
                                                          "X-Forwarded-For")
                            : NULL;
  if (!xff)
    return;
  char first[SRV_CLIENT_KEY];
  xff += strspn(xff, " \t");
  size_t n = strcspn(xff, ", \t");
  if (n == 0 || n >= sizeof first)
    return;
  memcpy(first, xff, n);
  first[n] = 0;
  srv_address_text(first, r->key, sizeof r->key); /* the peer if not */
}

static int is_json_type(const char *ct) {
  if (!ct)
    return 0;
  while (*ct == ' ')
    ct++;
  size_t n = strlen("application/json");
  return strncasecmp(ct, "application/json", n) == 0 &&
         (ct[n] == 0 || ct[n] == ';' || ct[n] == ' ');
}

typedef struct framing {
  int content_length, transfer_encoding, host;
} framing;

static enum MHD_Result count_header(void *cls, enum MHD_ValueKind kind,
                                    const char *key, const char *value) {
  framing *f = cls;
  (void)kind;
  (void)value;
  f->content_length += strcasecmp(key, "Content-Length") == 0;
  f->transfer_encoding += strcasecmp(key, "Transfer-Encoding") == 0;
  f->host += strcasecmp(key, "Host") == 0;
  return MHD_YES;
}

/* Headers that would let two parties read different requests out of the
 * same bytes; NULL when there are none. */
static const char *smuggling(struct MHD_Connection *c) {
  framing f = {0, 0, 0};
  MHD_get_connection_values(c, MHD_HEADER_KIND, count_header, &f);
  if (f.content_length > 1)
    return "more than one Content-Length header";
  if (f.content_length && f.transfer_encoding)
    return "Content-Length together with Transfer-Encoding";
  if (f.host > 1)
    return "more than one Host header";
  return NULL;
}

/* Decide an error answer now, send it on the next call. */
static enum MHD_Result defer(req *r, api_problem_kind kind, const char *detail,
                             const char *allow) {
  r->p_status = api_problem_status(kind);
  r->p_kind = kind;
  r->p_allow = allow;
  if (detail)
    snprintf(r->p_detail, sizeof r->p_detail, "%s", detail);
  return MHD_YES;
}

/* 413: the body is over the limit (from Content-Length, or as it came). */
static enum MHD_Result too_large(struct srv_daemon *d, struct MHD_Connection *c,
                                 req *r) {
  char detail[128];
  snprintf(detail, sizeof detail, "the body is over the limit of %zu bytes",
           d->cfg.lim.max_body);
  return send_problem(c, r, API_P_BODY_TOO_LARGE, detail, "max_body",
                      (double)d->cfg.lim.max_body, NULL);
}

/* The first call of a request: its headers are in.  Route it, and refuse
 * now what can be refused from the headers alone. */
/* The request's id: its X-Request-Id when that is 1 to SRV_REQUEST_ID
 * characters of [A-Za-z0-9._:-] (what a proxy or a client makes), else one
 * made here, 16 hex digits unique within the process's life. */
static void request_id(struct srv_daemon *d, struct MHD_Connection *c, req *r) {
  const char *h =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "X-Request-Id");
  size_t n = h ? strlen(h) : 0;
  int ok = n >= 1 && n <= SRV_REQUEST_ID;
  for (size_t i = 0; ok && i < n; i++) {
    char ch = h[i];
    ok = (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') ||
         (ch >= '0' && ch <= '9') || ch == '.' || ch == '_' || ch == ':' ||
         ch == '-';
  }
  if (ok) {
    memcpy(r->rid, h, n + 1);
    return;
  }
  /* splitmix64 of seed + counter: distinct for distinct counters */
  unsigned long long z =
      d->rid_seed +
      0x9e3779b97f4a7c15ULL * (atomic_fetch_add(&d->rid_next, 1) + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  z ^= z >> 31;
  snprintf(r->rid, sizeof r->rid, "%016llx", z);
}

static enum MHD_Result admit(struct srv_daemon *d, struct MHD_Connection *c,
                             req *r, const char *url, const char *method) {
  size_t ep;
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
  r->d = d;
  r->c = c;
  r->cn = ci ? ci->socket_context : NULL;
  if (r->cn)
    atomic_fetch_add(&r->cn->requests, 1);
  r->t0 = now();
  r->ep = api_endpoint_count();
  snprintf(r->method, sizeof r->method, "%s", method);
  snprintf(r->path, sizeof r->path, "%s", url);
  request_id(d, c, r);
  r->gzip = accepts_gzip(c);
  client_of(d, c, r);
  cors_of(d, c, r);
  srv_metrics_in_flight(d->metrics, +1);
  const char *bad = smuggling(c);
  if (bad) {
    r->close = 1;
    return send_problem(c, r, API_P_BAD_REQUEST, bad, NULL, 0, NULL);
  }
  if (atomic_load(&d->draining))
    return defer(r, API_P_SHUTTING_DOWN, "the server is shutting down", NULL);
  int route = api_route(method, url, &ep);
  if (route == 404)
    return defer(r, API_P_NOT_FOUND, "no such resource; see /openapi.json",
                 NULL);
  const api_endpoint *row = api_endpoint_at(ep);
  r->ep = ep;
  if (!strcmp(method, "OPTIONS")) {
    /* what the path takes; a browser's preflight (answered on the next
     * call, with CORS headers when the origin is allowed) */
    snprintf(r->preflight, sizeof r->preflight, "%s, OPTIONS", row->method);
    return MHD_YES;
  }
  if (route == 405) {
    snprintf(r->p_detail, sizeof r->p_detail, "%s takes %s", row->path,
             row->method);
    return defer(r, API_P_METHOD_NOT_ALLOWED, NULL, row->method);
  }
  if (row->run_class == API_RUN_INLINE)
    return MHD_YES; /* answered on the next call */
  r->is_post = 1;
  const char *ct =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Type");
  if (!is_json_type(ct))
    return defer(r, API_P_MEDIA_TYPE,
                 "send the body as Content-Type: application/json", NULL);
  const char *cl =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Length");
  if (cl) {
    char *end;
    errno = 0;
    unsigned long long n = strtoull(cl, &end, 10);
    if (errno == ERANGE || n > d->cfg.lim.max_body)
      return too_large(d, c, r);
  }
  return MHD_YES;
}

/* A piece of the body: kept while it fits the limit, counted over it. */
static enum MHD_Result take_body(struct srv_daemon *d, req *r, const char *data,
                                 size_t n) {
  if (r->too_big || r->len + n > d->cfg.lim.max_body) {
    r->too_big = 1;
    return MHD_YES;
  }
  if (r->over_budget || over_budget(d)) {
    r->over_budget = 1; /* answered 503 once the body is in */
    return MHD_YES;
  }
  if (r->len + n + 1 > r->cap) {
    size_t cap = r->cap ? r->cap : 4096;
    while (cap < r->len + n + 1)
      cap *= 2;
    char *b = realloc(r->buf, cap);
    if (!b)
      return MHD_NO;
    r->buf = b;
    r->cap = cap;
  }
  memcpy(r->buf + r->len, data, n);
  r->len += n;
  r->buf[r->len] = 0;
  hold(d, r, (long)n);
  return MHD_YES;
}

/* The request is wholly received: the monitor's deadline no longer runs. */
static void received(struct srv_daemon *d, req *r) {
  if (!r->cn)
    return;
  pthread_mutex_lock(&d->mu);
  r->cn->receiving = 0;
  pthread_mutex_unlock(&d->mu);
}

/* The body of a computation is in: refused at once while the daemon shuts
 * down or the memory budget is spent; else a batch starts its answer, and
 * any other request goes to the pool. */
static enum MHD_Result compute(struct srv_daemon *d, struct MHD_Connection *c,
                               req *r) {
  if (atomic_load(&d->draining))
    return send_problem(c, r, API_P_SHUTTING_DOWN,
                        "the server is shutting down", NULL, 0, NULL);
  if (r->over_budget || over_budget(d)) {
    api_response ar;
    budget_problem(d, &ar);
    return send_api(c, r, &ar, NULL);
  }
  if (api_endpoint_at(r->ep)->run_class == API_RUN_BATCH)
    return batch_start(d, c, r);
  return submit(d, c, r);
}

static enum MHD_Result handler(void *cls, struct MHD_Connection *c,
                               const char *url, const char *method,
                               const char *version, const char *upload_data,
                               size_t *upload_data_size, void **con_cls) {
  struct srv_daemon *d = cls;
  req *r = *con_cls;
  (void)version;
  if (!r) {
    if (!(r = calloc(1, sizeof *r)))
      return MHD_NO;
    *con_cls = r;
    return admit(d, c, r, url, method);
  }
  if (r->answered) /* resumed by the pool */
    return send_api(c, r, &r->ar, NULL);
  if (r->done || r->p_status) {
    /* an answer is decided: discard whatever body still comes */
    if (*upload_data_size || r->done) {
      *upload_data_size = 0;
      return MHD_YES;
    }
    received(d, r);
    return send_problem(c, r, r->p_kind, r->p_detail, NULL, 0, r->p_allow);
  }
  if (*upload_data_size) {
    size_t n = *upload_data_size;
    *upload_data_size = 0;
    return take_body(d, r, upload_data, n);
  }
  received(d, r);
  if (r->too_big)
    return too_large(d, c, r);
  if (r->preflight[0])
    return send_body(c, r, 204, NULL, 0, NULL, 0, r->preflight, 0);
  if (!r->is_post) {
    api_response ar;
    if (d->etags[r->ep][0]) {
      /* the contract and the explorer's files change only with the binary:
       * a validator and a lifetime, and 304 to a client that has them */
      r->etag = d->etags[r->ep];
      const char *inm =
          MHD_lookup_connection_value(c, MHD_HEADER_KIND, "If-None-Match");
      /* the validator of the representation that would be sent */
      char tag[40];
      snprintf(tag, sizeof tag, "%.*s%s\"", (int)strlen(r->etag) - 1, r->etag,
               r->gzip ? "-gzip" : "");
      if (inm && (strstr(inm, tag) || !strcmp(inm, "*")))
        return send_body(c, r, 304, NULL, 0, "application/json", 0, NULL, 0);
    }
    handle(d, r, &ar);
    return send_api(c, r, &ar, NULL);
  }
  return compute(d, c, r);
}

/* A JSON string's contents (the path is the client's text). */
static void json_text(FILE *f, const char *s) {
  for (; *s; s++) {
    unsigned char ch = (unsigned char)*s;
    if (ch == '"' || ch == '\\')
      fprintf(f, "\\%c", ch);
    else if (ch < 0x20 || ch >= 0x7f)
      fprintf(f, "\\u%04x", ch);
    else
      fputc(ch, f);
  }
}

/* One line per request on stderr: JSON (default) or the plain
 * "method path status us". */
static void access_log(const struct srv_daemon *d, const req *r, int status,
                       double dt) {
  long us = (long)(dt * 1e6);
  if (d->cfg.log_plain) {
    fprintf(stderr, "%s %s %d %ld\n", r->method, r->path, status, us);
    return;
  }
  struct timespec ts;
  struct tm tm;
  char when[32];
  clock_gettime(CLOCK_REALTIME, &ts);
  gmtime_r(&ts.tv_sec, &tm);
  strftime(when, sizeof when, "%Y-%m-%dT%H:%M:%S", &tm);
  flockfile(stderr);
  fprintf(stderr, "{\"time\":\"%s.%03ldZ\",\"request_id\":\"", when,
          ts.tv_nsec / 1000000);
  json_text(stderr, r->rid);
  fprintf(stderr, "\",\"client\":\"");
  json_text(stderr, r->key);
  fprintf(stderr, "\",\"method\":\"");
  json_text(stderr, r->method);
  fprintf(stderr, "\",\"path\":\"");
  json_text(stderr, r->path);
  fprintf(stderr, "\",\"status\":%d,\"bytes\":%zu,\"us\":%ld}\n", status,
          r->bytes, us);
  funlockfile(stderr);
}

static void completed(void *cls, struct MHD_Connection *c, void **con_cls,
                      enum MHD_RequestTerminationCode toe) {
  struct srv_daemon *d = cls;
  req *r = *con_cls;
  (void)c;
  (void)toe;
  if (!r)
    return;
  double dt = now() - r->t0;
  int status = r->done ? r->status : 499; /* 499: client went away */
  srv_metrics_observe(d->metrics, r->ep, status, dt);
  srv_metrics_in_flight(d->metrics, -1);
  if (r->batch)
    r->bytes = r->batch->sent;
  if (!d->cfg.quiet)
    access_log(d, r, status, dt);
  if (r->cn) {
    /* the next request on this connection has its own deadline */
    pthread_mutex_lock(&d->mu);
    r->cn->start = now();
    r->cn->receiving = 1;
    pthread_mutex_unlock(&d->mu);
  }
  if (r->batch)
    batch_detach(r->batch);
  srv_metrics_held(d->metrics, -r->held);
  api_response_free(&r->ar);
  free(r->buf);
  free(r);
  *con_cls = NULL;
}

/* ---- connections and the monitor ------------------------------------------
 */

static void client_key(struct MHD_Connection *c, char *key, size_t n) {
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
  const struct sockaddr *sa = ci ? ci->client_addr : NULL;
  snprintf(key, n, "?");
  if (sa && sa->sa_family == AF_INET)
    inet_ntop(AF_INET, &((const struct sockaddr_in *)sa)->sin_addr, key,
              (socklen_t)n);
  else if (sa && sa->sa_family == AF_INET6)
    inet_ntop(AF_INET6, &((const struct sockaddr_in6 *)sa)->sin6_addr, key,
              (socklen_t)n);
}

static int peer_port(struct MHD_Connection *c) {
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_CLIENT_ADDRESS);
  const struct sockaddr *sa = ci ? ci->client_addr : NULL;
  if (sa && sa->sa_family == AF_INET)
    return ntohs(((const struct sockaddr_in *)sa)->sin_port);
  if (sa && sa->sa_family == AF_INET6)
    return ntohs(((const struct sockaddr_in6 *)sa)->sin6_port);
  return 0;
}

static void connection(void *cls, struct MHD_Connection *c, void **socket_ctx,
                       enum MHD_ConnectionNotificationCode toe) {
  struct srv_daemon *d = cls;
  conn *cn = *socket_ctx;
  if (toe == MHD_CONNECTION_NOTIFY_STARTED) {
    atomic_fetch_add(&d->conns_started, 1);
    const union MHD_ConnectionInfo *ci =
        MHD_get_connection_info(c, MHD_CONNECTION_INFO_CONNECTION_FD);
    if (!ci || !(cn = calloc(1, sizeof *cn)))
      return;
    cn->fd = ci->connect_fd;
    cn->start = now();
    cn->receiving = 1;
    client_key(c, cn->key, sizeof cn->key);
    cn->peer_port = peer_port(c);
    pthread_mutex_lock(&d->mu);
    cn->next = d->conns;
    if (d->conns)
      d->conns->prev = cn;
    d->conns = cn;
    pthread_mutex_unlock(&d->mu);
    *socket_ctx = cn;
    return;
  }
  if (!cn)
    return;
  pthread_mutex_lock(&d->mu);
  if (cn->prev)
    cn->prev->next = cn->next;
  else
    d->conns = cn->next;
  if (cn->next)
    cn->next->prev = cn->prev;
  pthread_mutex_unlock(&d->mu);
  free(cn);
  *socket_ctx = NULL;
}

/* Close the connections that are past their deadline for a request. */
static void reap_slow(struct srv_daemon *d) {
  double t = now();
  pthread_mutex_lock(&d->mu);
  for (conn *cn = d->conns; cn; cn = cn->next)
    if (cn->receiving && !cn->shut && t - cn->start > d->cfg.request_timeout) {
      shutdown(cn->fd, SHUT_RDWR);
      cn->shut = 1;
      srv_metrics_slow(d->metrics);
    }
  pthread_mutex_unlock(&d->mu);
}

static void *monitor(void *arg) {
  struct srv_daemon *d = arg;
  struct timespec ts = {0, MONITOR_MS * 1000000L};
  while (!atomic_load(&d->monitor_stop)) {
    srv_pool_watch(d->pool);
    reap_slow(d);
    nanosleep(&ts, NULL);
  }
  return NULL;
}

/* ---- start and stop --------------------------------------------------------
 */

/* The listening address of --bind and --port; 0, or -1 when --bind is not
 * an IPv4 or IPv6 address. */
static int listen_address(const srv_config *cfg, struct sockaddr_storage *ss,
                          unsigned *flags) {
  memset(ss, 0, sizeof *ss);
  if (strchr(cfg->bind, ':')) {
    struct sockaddr_in6 *a = (struct sockaddr_in6 *)ss;
    a->sin6_family = AF_INET6;
    a->sin6_port = htons((uint16_t)cfg->port);
    *flags |= MHD_USE_IPv6;
    return inet_pton(AF_INET6, cfg->bind, &a->sin6_addr) == 1 ? 0 : -1;
  }
  struct sockaddr_in *a = (struct sockaddr_in *)ss;
  a->sin_family = AF_INET;
  a->sin_port = htons((uint16_t)cfg->port);
  return inet_pton(AF_INET, cfg->bind, &a->sin_addr) == 1 ? 0 : -1;
}

/* The port the daemon listens on (the one the system chose for --port 0). */
static int bound_port(struct MHD_Daemon *mhd, int asked) {
  const union MHD_DaemonInfo *info =
      MHD_get_daemon_info(mhd, MHD_DAEMON_INFO_LISTEN_FD);
  struct sockaddr_storage got;
  socklen_t gl = sizeof got;
  if (!info || getsockname(info->listen_fd, (struct sockaddr *)&got, &gl))
    return asked;
  return got.ss_family == AF_INET6
             ? ntohs(((struct sockaddr_in6 *)&got)->sin6_port)
             : ntohs(((struct sockaddr_in *)&got)->sin_port);
}

/* Enough descriptors for every connection the flags allow. */
static void raise_fd_limit(unsigned max_conn) {
  struct rlimit rl;
  if (getrlimit(RLIMIT_NOFILE, &rl) != 0)
    return;
  rlim_t want = (rlim_t)max_conn + 64;
  if (rl.rlim_cur < want) {
    rl.rlim_cur = rl.rlim_max < want ? rl.rlim_max : want;
    setrlimit(RLIMIT_NOFILE, &rl);
  }
}

static void daemon_free(struct srv_daemon *d) {
  if (d->monitor_running) {
    atomic_store(&d->monitor_stop, 1);
    pthread_join(d->monitor, NULL);
  }
  srv_pool_free(d->pool);
  srv_metrics_free(d->metrics);
  pthread_mutex_destroy(&d->mu);
  free(d->etags);
  free(d);
}

struct srv_daemon *srv_start(const srv_config *cfg) {
  struct srv_daemon *d = calloc(1, sizeof *d);
  struct sockaddr_storage ss;
  unsigned flags = MHD_USE_EPOLL_INTERNAL_THREAD | MHD_ALLOW_SUSPEND_RESUME |
                   MHD_USE_ERROR_LOG;
  if (!d)
    return NULL;
  pthread_mutex_init(&d->mu, NULL);
  d->cfg = *cfg;
  if (d->cfg.batch_parallel == 0)
    d->cfg.batch_parallel = d->cfg.workers ? d->cfg.workers : 1;
  d->started = now();
  snprintf(d->transport, sizeof d->transport, "%s", MHD_get_version());
  if (getentropy(&d->rid_seed, sizeof d->rid_seed) != 0)
    d->rid_seed = (unsigned long long)time(NULL) * 0x9e3779b97f4a7c15ULL ^
                  (unsigned long long)getpid();
  /* the static answers' validators: FNV-1a of their bytes */
  if (!(d->etags = calloc(api_endpoint_count(), sizeof *d->etags))) {
    daemon_free(d);
    return NULL;
  }
  for (size_t i = 0; i < api_endpoint_count(); i++) {
    size_t n;
    const char *s = api_static_body(i, &n);
    unsigned long long h = 0xcbf29ce484222325ULL;
    for (size_t k = 0; s && k < n; k++)
      h = (h ^ (unsigned char)s[k]) * 0x100000001b3ULL;
    if (s)
      snprintf(d->etags[i], sizeof d->etags[i], "\"%016llx\"", h);
  }
  srv_pool_cfg pc = {cfg->workers, cfg->client_workers, cfg->client_queue};
  if (!(d->metrics = srv_metrics_new()) || !(d->pool = srv_pool_new(&pc))) {
    daemon_free(d);
    return NULL;
  }
  srv_metrics_build(d->metrics, api_version(), d->transport);
  if (listen_address(cfg, &ss, &flags)) {
    fprintf(stderr, "stickslipd: --bind %s is not an IPv4 or IPv6 address\n",
            cfg->bind);
    daemon_free(d);
    return NULL;
  }
  raise_fd_limit(cfg->max_conn);
  d->mhd = MHD_start_daemon(
      flags, (uint16_t)cfg->port, NULL, NULL, handler, d, MHD_OPTION_SOCK_ADDR,
      (struct sockaddr *)&ss, MHD_OPTION_CONNECTION_LIMIT, cfg->max_conn,
      MHD_OPTION_PER_IP_CONNECTION_LIMIT, cfg->per_ip,
      MHD_OPTION_CONNECTION_TIMEOUT, cfg->timeout,
      MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)CONN_MEMORY,
      MHD_OPTION_STRICT_FOR_CLIENT, (int)1, MHD_OPTION_NOTIFY_COMPLETED,
      completed, d, MHD_OPTION_NOTIFY_CONNECTION, connection, d,
      MHD_OPTION_END);
  if (!d->mhd) {
    fprintf(stderr, "stickslipd: cannot listen on %s port %d: %s\n", cfg->bind,
            cfg->port, strerror(errno));
    daemon_free(d);
    return NULL;
  }
  if (pthread_create(&d->monitor, NULL, monitor, d) == 0)
    d->monitor_running = 1;
  int port = d->port = bound_port(d->mhd, cfg->port);
  if (strchr(cfg->bind, ':'))
    fprintf(stderr, "stickslipd listening on http://[%s]:%d\n", cfg->bind,
            port);
  else
    fprintf(stderr, "stickslipd listening on http://%s:%d\n", cfg->bind, port);
  fflush(stderr);
  return d;
}

int srv_add_connection(struct srv_daemon *d, int fd,
                       const struct sockaddr *addr, unsigned addrlen) {
  return MHD_add_connection(d->mhd, fd, addr, (socklen_t)addrlen) == MHD_YES
             ? 0
             : -1;
}

int srv_port(struct srv_daemon *d) { return d->port; }

unsigned long srv_connections_started(struct srv_daemon *d) {
  return atomic_load(&d->conns_started);
}

int srv_connection_watched(struct srv_daemon *d, int fd, int peer_port,
                           srv_conn_state *st) {
  int found = -1;
  pthread_mutex_lock(&d->mu);
  for (conn *cn = d->conns; cn && found; cn = cn->next)
    if (fd >= 0 ? cn->fd == fd : cn->peer_port == peer_port) {
      st->receiving = cn->receiving;
      st->shut = cn->shut;
      st->age = now() - cn->start;
      st->requests = atomic_load(&cn->requests);
      st->suspended = atomic_load(&cn->suspended);
      st->resumed = atomic_load(&cn->resumed);
      found = 0;
    }
  pthread_mutex_unlock(&d->mu);
  return found;
}

static void wait_in_flight(struct srv_daemon *d, double until) {
  struct timespec ts = {0, 10 * 1000 * 1000};
  while (srv_metrics_in_flight(d->metrics, 0) > 0 && now() < until)
    nanosleep(&ts, NULL);
}

void srv_stop(struct srv_daemon *d) {
  if (!d)
    return;
  /* new connections are refused from now on */
  atomic_store(&d->draining, 1);
  MHD_socket fd = MHD_quiesce_daemon(d->mhd);
  if (fd != MHD_INVALID_SOCKET)
    close(fd);
  /* what waits is answered 503; what runs finishes within the drain, or is
   * stopped after it; every suspended request is resumed before the
   * daemon stops, as libmicrohttpd requires */
  srv_pool_drain(d->pool);
  double until = now() + d->cfg.drain;
  if (!srv_pool_wait_idle(d->pool, d->cfg.drain)) {
    srv_pool_cancel_all(d->pool);
    srv_pool_wait_idle(d->pool, 5);
  }
  wait_in_flight(d, until > now() + 1 ? until : now() + 1);
  atomic_store(&d->monitor_stop, 1);
  if (d->monitor_running)
    pthread_join(d->monitor, NULL);
  d->monitor_running = 0;
  MHD_stop_daemon(d->mhd);
  daemon_free(d);
}
