/*
 * request.c: a request, from its headers to its completion.
 *
 * Admission.  The first call of libmicrohttpd's handler has the headers:
 * the request gets its id (X-Request-Id, given or made), its client (the
 * peer, or X-Forwarded-For from a trusted proxy), its route, and what can
 * be refused from the headers alone is decided then.  Framing that could
 * smuggle a request or that libmicrohttpd 0.9.75 reads loosely (two
 * Content-Length headers, Content-Length with Transfer-Encoding, a
 * Transfer-Encoding other than one "chunked", whitespace between a
 * header's name and its colon, a space in the target, no Host or two) is
 * refused with 400 and the connection is closed, before libmicrohttpd acts
 * on it; a header block too large to leave room for an answer's headers is
 * refused with 413, written to the socket directly.
 *
 * Compute.  A request that computes is suspended once its body is in
 * (MHD_suspend_connection), handed to the pool (pool.c: per-client queues,
 * round robin, a bounded queue per client, at most client_workers running
 * per client), and resumed with its answer by the worker that computed it.
 * What needs no computing (the api's inline endpoints, and every refusal)
 * is answered on the I/O thread at once, and so is a computation the api
 * calls small and bounded (an /orbit from a guess) when it is the only
 * request in flight and the pool idles (answer_small).  POST /batch is
 * batch.c's: its body is parsed in the pool too, and its answer started when
 * the request is resumed.  Nothing whose work grows with the body runs on the
 * I/O thread, which only collects the bytes.
 *
 * Completion.  Metrics, one line of access log, and the connection's
 * deadline for its next request.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "internal.h"

/* ---- admission: what the headers say ------------------------------------- */

int srv_address_text(const char *s, char *out, size_t n) {
  unsigned char ip[16];
  int af = inet_pton(AF_INET, s, ip) == 1    ? AF_INET
           : inet_pton(AF_INET6, s, ip) == 1 ? AF_INET6
                                             : 0;
  return af && inet_ntop(af, ip, out, (socklen_t)n) ? 0 : -1;
}

int srv__trusted(const struct srv_daemon *d, const char *addr) {
  for (int i = 0; i < d->cfg.n_trusted; i++)
    if (strcmp(addr, d->cfg.trusted[i]) == 0)
      return 1;
  return 0;
}

static enum MHD_Result last_xff(void *cls, enum MHD_ValueKind kind,
                                const char *key, const char *value) {
  (void)kind;
  if (strcasecmp(key, "X-Forwarded-For") == 0)
    *(const char **)cls = value;
  return MHD_YES;
}

/* The client of a request: the peer's address, or, when the peer is a
 * trusted proxy, the rightmost address of X-Forwarded-For that a trusted
 * proxy did not add: each proxy appends the address it got the request
 * from, so the addresses right of the client's were written by proxies,
 * and the ones left of it by the client, who can write anything.  Walked
 * from the right of the last X-Forwarded-For header, past the trusted
 * proxies; an entry that is not an address leaves the peer. */
static void client_of(const struct srv_daemon *d, struct MHD_Connection *c,
                      srv__req *r) {
  const char *peer = r->cn ? r->cn->key : "?";
  snprintf(r->key, sizeof r->key, "%s", peer);
  const char *xff = NULL;
  if (!srv__trusted(d, peer))
    return;
  MHD_get_connection_values(c, MHD_HEADER_KIND, last_xff, &xff);
  for (size_t end = xff ? strlen(xff) : 0; end > 0;) {
    size_t start = end;
    while (start > 0 && xff[start - 1] != ',')
      start--;
    size_t a = start, b = end;
    while (a < b && (xff[a] == ' ' || xff[a] == '\t'))
      a++;
    while (b > a && (xff[b - 1] == ' ' || xff[b - 1] == '\t'))
      b--;
    char addr[SRV_CLIENT_KEY], text[SRV_CLIENT_KEY];
    if (b - a == 0 || b - a >= sizeof addr)
      return;
    memcpy(addr, xff + a, b - a);
    addr[b - a] = 0;
    if (srv_address_text(addr, text, sizeof text))
      return;
    snprintf(r->key, sizeof r->key, "%s", text);
    if (!srv__trusted(d, text))
      return;
    end = start > 0 ? start - 1 : 0;
  }
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
  int content_length, transfer_encoding, host, te_other, name_space, headers;
} framing;

static enum MHD_Result count_header(void *cls, enum MHD_ValueKind kind,
                                    const char *key, const char *value) {
  framing *f = cls;
  (void)kind;
  f->headers++;
  f->content_length += strcasecmp(key, "Content-Length") == 0;
  f->host += strcasecmp(key, "Host") == 0;
  if (strcasecmp(key, "Transfer-Encoding") == 0) {
    f->transfer_encoding++;
    f->te_other += !value || strcasecmp(value, "chunked") != 0;
  }
  f->name_space += key[strcspn(key, " \t")] != 0;
  return MHD_YES;
}

/* Framing that would let two parties read different requests out of the
 * same bytes, or that libmicrohttpd would read loosely (a header named
 * "Content-Length " is not its length; a Transfer-Encoding it does not
 * know has it read the body until the connection closes); NULL when there
 * is none.  @a f: the counts, for the caller. */
static const char *smuggling(struct MHD_Connection *c, const char *version,
                             framing *f) {
  MHD_get_connection_values(c, MHD_HEADER_KIND, count_header, f);
  if (f->name_space)
    return "whitespace between a header's name and its colon";
  if (f->content_length > 1)
    return "more than one Content-Length header";
  if (f->content_length && f->transfer_encoding)
    return "Content-Length together with Transfer-Encoding";
  if (f->transfer_encoding > 1 || f->te_other)
    return "a Transfer-Encoding other than one \"chunked\"";
  if (f->host > 1)
    return "more than one Host header";
  if (!f->host && strcmp(version, MHD_HTTP_VERSION_1_1) == 0)
    return "an HTTP/1.1 request without a Host header";
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
  const srv__conn *cn = ci ? ci->socket_context : NULL;
  if (cn && cn->space_in_target)
    return "a space in the request target";
  return NULL;
}

void *srv__target(void *cls, const char *uri, struct MHD_Connection *c) {
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
  srv__conn *cn = ci ? ci->socket_context : NULL;
  (void)cls;
  if (cn)
    cn->space_in_target = strchr(uri, ' ') != NULL;
  return NULL; /* the request's context is made by the handler */
}

/* What a header block may take of a connection's memory, so that an
 * answer's headers still fit: its bytes, and about 64 per header for
 * libmicrohttpd's record of it. */
static size_t header_room(struct MHD_Connection *c, const framing *f) {
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_REQUEST_HEADER_SIZE);
  return (ci ? ci->header_size : 0) + 64 * (size_t)f->headers;
}

/* Decide an error answer now, send it on the next call. */
enum MHD_Result srv__defer(srv__req *r, api_problem_kind kind,
                           const char *detail, const char *allow) {
  r->p_status = api_problem_status(kind);
  r->p_kind = kind;
  r->p_allow = allow;
  if (detail)
    snprintf(r->p_detail, sizeof r->p_detail, "%s", detail);
  return MHD_YES;
}

/* The body limit of request @a r: a job's (Prefer: respond-async) is
 * --max-job-body, decided from the headers before any byte of the body. */
static size_t body_limit(const struct srv_daemon *d, const srv__req *r,
                         const char **name) {
  *name = r->async ? "max_job_body" : "max_body";
  return r->async ? d->cfg.max_job_body : d->cfg.lim.max_body;
}

/* 413: the body is over the limit (from Content-Length, or as it came). */
static enum MHD_Result too_large(struct srv_daemon *d, struct MHD_Connection *c,
                                 srv__req *r) {
  char detail[128];
  const char *name;
  size_t max = body_limit(d, r, &name);
  snprintf(detail, sizeof detail, "the body is over the limit of %zu bytes",
           max);
  return srv__send_problem(c, r, API_P_BODY_TOO_LARGE, detail, name,
                           (double)max, NULL);
}

/* The request's id: its X-Request-Id when that is 1 to SRV_REQUEST_ID
 * characters of [A-Za-z0-9._:-] (what a proxy or a client makes), else one
 * made here, 16 hex digits unique within the process's life. */
static void request_id(struct srv_daemon *d, struct MHD_Connection *c,
                       srv__req *r) {
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

/* ---- the pages of the problem types -------------------------------------- */

#define PAGE_PREFIX "/problems/"

/* GET /problems/<type>, the page that a problem's type URI names: routed
 * here, written by the api (api_problem_page).  1 when @a url is one. */
static int page_admit(srv__req *r, const char *url, const char *method) {
  if (strncmp(url, PAGE_PREFIX, sizeof PAGE_PREFIX - 1))
    return 0;
  r->page = 1;
  if (!strcmp(method, "OPTIONS")) {
    snprintf(r->preflight, sizeof r->preflight, "GET, OPTIONS");
  } else if (strcmp(method, "GET") && strcmp(method, "HEAD")) {
    snprintf(r->p_detail, sizeof r->p_detail, "this resource takes GET");
    srv__defer(r, API_P_METHOD_NOT_ALLOWED, NULL, "GET");
  } else if (strlen(url) >= sizeof r->path) {
    srv__defer(r, API_P_NOT_FOUND, "no such problem type", NULL);
  }
  return 1;
}

/* Whether the client asks for HTML: its Accept names text/html with a
 * weight above 0, as a browser's does; curl's (any type) and application/json
 * get JSON. */
static int accepts_html(struct MHD_Connection *c) {
  const char *a = MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Accept");
  for (const char *p = a; p && *p; p += strcspn(p, ",")) {
    p += strspn(p, ", \t");
    if (strncasecmp(p, "text/html", 9) || (p[9] && !strchr(",; \t", p[9])))
      continue;
    const char *q = strstr(p, "q=");
    size_t n = strcspn(p, ",");
    if (!q || q > p + n || strtod(q + 2, NULL) > 0)
      return 1;
  }
  return 0;
}

static enum MHD_Result send_page(struct MHD_Connection *c, srv__req *r) {
  api_response ar;
  api_problem_page(r->path + sizeof PAGE_PREFIX - 1, accepts_html(c), &ar);
  r->vary_accept = 1;
  return srv__send_api(c, r, &ar, NULL);
}

/* The first call of a request: its headers are in.  Route it, and refuse
 * now what can be refused from the headers alone. */
static enum MHD_Result admit(struct srv_daemon *d, struct MHD_Connection *c,
                             srv__req *r, const char *url, const char *method,
                             const char *version) {
  size_t ep;
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_SOCKET_CONTEXT);
  r->d = d;
  r->c = c;
  r->cn = ci ? ci->socket_context : NULL;
  if (r->cn) {
    atomic_fetch_add(&r->cn->requests, 1);
    r->cn->req = r;
  }
  r->t0 = srv__now();
  r->ep = api_endpoint_count();
  snprintf(r->method, sizeof r->method, "%s", method);
  snprintf(r->path, sizeof r->path, "%s", url);
  request_id(d, c, r);
  r->gzip = srv__accepts_gzip(c);
  client_of(d, c, r);
  srv__cors_of(d, c, r);
  srv_metrics_in_flight(d->metrics, +1);
  framing f = {0, 0, 0, 0, 0, 0};
  const char *bad = smuggling(c, version, &f);
  if (header_room(c, &f) > SRV__HEADER_ROOM) {
    /* libmicrohttpd has no room left to build an answer's headers */
    char detail[128];
    snprintf(detail, sizeof detail,
             "the header block is over the limit of %d bytes",
             SRV__HEADER_ROOM);
    srv__send_raw_problem(r, API_P_BODY_TOO_LARGE, detail, "max_header",
                          SRV__HEADER_ROOM);
    return MHD_YES;
  }
  if (bad) {
    r->close = 1;
    return srv__send_problem(c, r, API_P_BAD_REQUEST, bad, NULL, 0, NULL);
  }
  if (atomic_load(&d->draining))
    return srv__defer(r, API_P_SHUTTING_DOWN, "the server is shutting down",
                      NULL);
  if (srv__jobs_admit(d, c, r, url, method) || page_admit(r, url, method))
    return MHD_YES; /* /jobs..., /problems/...: answered on the last call */
  if (srv__docs_admit(r, url, method))
    return MHD_YES; /* /docs...: likewise */
  int route = api_route(method, url, &ep);
  if (route == 404)
    return srv__defer(r, API_P_NOT_FOUND, "no such resource; see /openapi.json",
                      NULL);
  const api_endpoint *row = api_endpoint_at(ep);
  r->ep = ep;
  r->form = api_negotiate(ep, MHD_lookup_connection_value(
                                  c, MHD_HEADER_KIND, MHD_HTTP_HEADER_ACCEPT));
  if (!strcmp(method, "OPTIONS")) {
    /* what the path takes; a browser's preflight (answered on the next
     * call, with CORS headers when the origin is allowed) */
    snprintf(r->preflight, sizeof r->preflight, "%s, OPTIONS", row->method);
    return MHD_YES;
  }
  if (route == 405) {
    snprintf(r->p_detail, sizeof r->p_detail, "%s takes %s", row->path,
             row->method);
    return srv__defer(r, API_P_METHOD_NOT_ALLOWED, NULL, row->method);
  }
  if (row->run_class == API_RUN_INLINE)
    return MHD_YES; /* answered on the next call */
  r->is_post = 1;
  r->async = d->jobs && srv__prefers_async(c); /* --no-jobs: ignored */
  const char *ct =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Type");
  if (!is_json_type(ct))
    return srv__defer(r, API_P_MEDIA_TYPE,
                      "send the body as Content-Type: application/json", NULL);
  const char *ce =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Encoding");
  if (ce && strcasecmp(ce, "identity") != 0) {
    /* RFC 9110 15.5.16: the answer names the codings taken */
    char detail[128];
    r->accept_encoding = "identity";
    snprintf(detail, sizeof detail,
             "a body with Content-Encoding %.24s is not taken: send it as "
             "identity (uncompressed)",
             ce);
    return srv__defer(r, API_P_MEDIA_TYPE, detail, NULL);
  }
  const char *cl =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "Content-Length");
  if (cl) {
    char *end;
    errno = 0;
    unsigned long long n = strtoull(cl, &end, 10);
    const char *name;
    if (errno == ERANGE || n > body_limit(d, r, &name))
      return too_large(d, c, r);
    r->expect = (size_t)n;
  }
  return MHD_YES;
}

/* ---- the body ------------------------------------------------------------ */

/* A piece of the body: kept while it fits the limit, counted over it. */
static enum MHD_Result take_body(struct srv_daemon *d, srv__req *r,
                                 const char *data, size_t n) {
  const char *name;
  size_t max = body_limit(d, r, &name);
  if (r->len + n > max) {
    /* libmicrohttpd takes no answer while a body comes: written to the
     * socket, so that a chunk that never ends (a chunk size of 2^64-1)
     * is not waited for */
    char detail[128];
    snprintf(detail, sizeof detail, "the body is over the limit of %zu bytes",
             max);
    srv__send_raw_problem(r, API_P_BODY_TOO_LARGE, detail, name, (double)max);
    return MHD_YES;
  }
  if (r->over_budget || srv__over_budget(d, r->key)) {
    r->over_budget = 1; /* answered 503 once the body is in */
    return MHD_YES;
  }
  if (r->len + n + 1 > r->cap) {
    /* room for the whole body at once when its length was told (it is
     * within the limit), else twice as much as needed; the room is what
     * the budget counts */
    size_t cap = r->cap ? r->cap : 4096;
    if (r->expect >= r->len + n)
      cap = r->expect + 1;
    while (cap < r->len + n + 1)
      cap *= 2;
    char *b = realloc(r->buf, cap);
    if (!b)
      return MHD_NO;
    r->buf = b;
    srv__hold(d, r, (long)(cap - r->cap));
    r->cap = cap;
  }
  memcpy(r->buf + r->len, data, n);
  r->len += n;
  r->buf[r->len] = 0;
  return MHD_YES;
}

/* ---- the api's answer ---------------------------------------------------- */

/* One request to the api, with what the daemon knows of itself. */
static void handle(struct srv_daemon *d, srv__req *r, api_response *ar) {
  api_server_info info = srv__server_info(d, &r->job);
  info.form = r->form;
  api_handle(r->ep, r->buf ? r->buf : "", r->len, &d->cfg.lim, &info, ar);
  if (ar->status >= 500 && ar->status != 503)
    fprintf(stderr, "stickslipd: %s %s answered %d: %.200s\n", r->method,
            r->path, ar->status, ar->body ? ar->body : "");
}

/* ---- the pool's side of a request ---------------------------------------- */

static void job_queued(srv_job *j) {
  srv__req *r = (srv__req *)j;
  if (r->cn)
    atomic_fetch_add(&r->cn->suspended, 1);
  MHD_suspend_connection(r->c);
}

/* Has the client of a suspended request gone away?  While a connection is
 * suspended libmicrohttpd does not look at its socket, so the monitor asks
 * here. */
static int job_gone(srv_job *j) {
  srv__req *r = (srv__req *)j;
  return r->cn && srv__peer_closed(r->cn->fd);
}

/* The memory budget is checked again when the work starts: what was
 * queued while it was free may find it spent. */
static void job_run(srv_job *j) {
  srv__req *r = (srv__req *)j;
  if (srv__over_budget(r->d, r->key))
    srv__budget_problem(r->d, r->key, &r->ar);
  else if (r->async || r->jobs)
    srv__jobs_run(r);
  else if (api_endpoint_at(r->ep)->run_class == API_RUN_BATCH)
    srv__batch_open(r);
  else
    handle(r->d, r, &r->ar);
  /* the answer counts from now on, not from when it is sent */
  srv__hold(r->d, r, (long)r->ar.held);
  r->ar.held = 0;
  /* the body is no longer needed: give its bytes back now */
  free(r->buf);
  r->buf = NULL;
  srv__hold(r->d, r, -(long)r->cap);
  r->len = r->cap = 0;
}

/* Back to the I/O thread with an answer: the pool is done with the job. */
static void job_done(srv_job *j) {
  srv__req *r = (srv__req *)j;
  if (j->state != SRV_JOB_DONE) {
    api_batch_free(r->ab); /* a batch's items not to be run */
    r->ab = NULL;
  }
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
enum MHD_Result srv__submit(struct srv_daemon *d, struct MHD_Connection *c,
                            srv__req *r) {
  r->job.ops = &REQUEST_JOB;
  r->job.kind = (unsigned)r->ep; /* the row of its endpoint in the metrics */
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
    return srv__send_problem(c, r, API_P_OVERLOADED, detail, NULL, 0, NULL);
  }
  return srv__send_problem(
      c, r, rc == SRV_POOL_NOMEM ? API_P_OUT_OF_MEMORY : API_P_SHUTTING_DOWN,
      "the computation could not be queued", NULL, 0, NULL);
}

/* A body no larger than this may be answered on the I/O thread. */
#define SMALL_BODY 2048

/* Answer @a r at once, on the I/O thread, when its work is small and
 * bounded (the api says: an /orbit from a guess, about 10 us), it is the
 * only request in flight and the pool is idle, so that it takes no turn
 * from queued work: a hand-off to a worker and back (two thread wake-ups,
 * a suspended connection resumed) costs several times such a computation.
 * With other requests in flight the pool's workers compute beside the I/O
 * thread, which alone would hold the throughput to one core.  0 when it is
 * not answered here. */
static int answer_small(struct srv_daemon *d, struct MHD_Connection *c,
                        srv__req *r, enum MHD_Result *ok) {
  if (r->len > SMALL_BODY || r->async ||
      api_endpoint_at(r->ep)->run_class != API_RUN_COMPUTE ||
      srv_metrics_in_flight(d->metrics, 0) > 1 || !srv_pool_idle(d->pool))
    return 0;
  api_response ar;
  api_server_info info = srv__server_info(d, &r->job);
  info.small_only = 1;
  /* not a job of the pool: no threads to borrow, nothing to cancel */
  info.threads = NULL;
  info.cancelled = NULL;
  if (api_handle(r->ep, r->buf ? r->buf : "", r->len, &d->cfg.lim, &info,
                 &ar) == 0)
    return 0;
  *ok = srv__send_api(c, r, &ar, NULL);
  return 1;
}

/* The body of a computation is in: refused at once while the daemon shuts
 * down or the memory budget (or the client's share of it) is spent; else it
 * is answered at once when small, or goes to the pool (a batch's body to be
 * parsed there). */
static enum MHD_Result compute(struct srv_daemon *d, struct MHD_Connection *c,
                               srv__req *r) {
  enum MHD_Result ok;
  if (atomic_load(&d->draining))
    return srv__send_problem(c, r, API_P_SHUTTING_DOWN,
                             "the server is shutting down", NULL, 0, NULL);
  if (r->over_budget || srv__over_budget(d, r->key)) {
    api_response ar;
    srv__budget_problem(d, r->key, &ar);
    return srv__send_api(c, r, &ar, NULL);
  }
  if (answer_small(d, c, r, &ok))
    return ok;
  return srv__submit(d, c, r);
}

int srv__not_modified(struct MHD_Connection *c, const srv__req *r) {
  const char *inm =
      MHD_lookup_connection_value(c, MHD_HEADER_KIND, "If-None-Match");
  /* the validator of the representation that would be sent */
  char tag[40];
  snprintf(tag, sizeof tag, "%.*s%s\"", (int)strlen(r->etag) - 1, r->etag,
           r->gzip ? "-gzip" : "");
  return inm && (strstr(inm, tag) || !strcmp(inm, "*"));
}

/* ---- libmicrohttpd's callbacks ------------------------------------------- */

/* libmicrohttpd's handler: called with the headers, with each piece of the
 * body, once the body is in, and again when the pool resumes the
 * connection. */
enum MHD_Result srv__handler(void *cls, struct MHD_Connection *c,
                             const char *url, const char *method,
                             const char *version, const char *upload_data,
                             size_t *upload_data_size, void **con_cls) {
  struct srv_daemon *d = cls;
  srv__req *r = *con_cls;
  if (!r) {
    if (!(r = calloc(1, sizeof *r)))
      return MHD_NO;
    *con_cls = r;
    return admit(d, c, r, url, method, version);
  }
  if (r->raw) {
    /* answered on the socket: discard the rest, close once it is in */
    if (!*upload_data_size)
      return MHD_NO;
    *upload_data_size = 0;
    return MHD_YES;
  }
  if (r->answered) /* resumed by the pool */
    return r->ab     ? srv__batch_start(d, c, r)
           : r->jobs ? srv__jobs_resumed(d, c, r)
                     : srv__send_api(c, r, &r->ar, NULL);
  if (r->done || r->p_status) {
    /* an answer is decided: discard whatever body still comes */
    if (*upload_data_size || r->done) {
      *upload_data_size = 0;
      return MHD_YES;
    }
    srv__receiving(d, r->cn, 0); /* the monitor's deadline no longer runs */
    return srv__send_problem(c, r, r->p_kind, r->p_detail, NULL, 0, r->p_allow);
  }
  if (*upload_data_size) {
    size_t n = *upload_data_size;
    *upload_data_size = 0;
    return take_body(d, r, upload_data, n);
  }
  srv__receiving(d, r->cn, 0);
  if (r->preflight[0])
    return srv__send_body(c, r, 204, NULL, 0, NULL, 0, r->preflight, 0);
  if (r->jobs) /* the store is read in the pool (jobs_http.c) */
    return srv__submit(d, c, r);
  if (r->doc)
    return srv__docs_answer(c, r);
  if (r->page)
    return send_page(c, r);
  if (!r->is_post) {
    api_response ar;
    if (d->etags[r->ep][0]) {
      /* the contract and the explorer's files change only with the binary:
       * a validator and a lifetime, and 304 to a client that has them */
      r->etag = d->etags[r->ep];
      if (srv__not_modified(c, r))
        return srv__send_body(c, r, 304, NULL, 0, "application/json", 0, NULL,
                              0);
    }
    handle(d, r, &ar);
    return srv__send_api(c, r, &ar, NULL);
  }
  return compute(d, c, r);
}

/* ---- completion: metrics and the access log ------------------------------ */

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

/* The plain log's text of a client's string: a control character, a
 * space, a backslash or a byte outside ASCII as \xHH, so that a line is
 * one request and its fields are split by spaces (a path of
 * "/%0d%0aGET / 200 1" forges no line; a terminal escape is not one). */
static void plain_text(FILE *f, const char *s) {
  for (; *s; s++) {
    unsigned char ch = (unsigned char)*s;
    if (ch <= 0x20 || ch >= 0x7f || ch == '\\')
      fprintf(f, "\\x%02x", ch);
    else
      fputc(ch, f);
  }
}

/* One line per request on stderr: JSON (default) or the plain
 * "method path status us". */
static void access_log(const struct srv_daemon *d, const srv__req *r,
                       int status, double dt) {
  long us = (long)(dt * 1e6);
  if (d->cfg.log_plain) {
    flockfile(stderr);
    plain_text(stderr, r->method);
    fputc(' ', stderr);
    plain_text(stderr, r->path);
    fprintf(stderr, " %d %ld\n", status, us);
    funlockfile(stderr);
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

/* libmicrohttpd's NOTIFY_COMPLETED: the request is answered, or its client
 * gone: before its answer was queued, or while it was being sent (a stream
 * cut, a batch's included); both are 499, as nginx logs them. */
/* The status of an answer libmicrohttpd made itself, for a request the
 * daemon had not answered yet: its error pages for what it refuses while a
 * body comes (a malformed chunk, a chunk size over 2^64; a chunk line too
 * long for the connection's memory, which 0.9.75 answers 500, wire.c
 * refuses first).  @a otherwise when it made none: the client went
 * away. */
static int library_status(struct MHD_Connection *c, int otherwise) {
  const union MHD_ConnectionInfo *ci =
      MHD_get_connection_info(c, MHD_CONNECTION_INFO_HTTP_STATUS);
  return ci ? (int)ci->http_status : otherwise;
}

void srv__completed(void *cls, struct MHD_Connection *c, void **con_cls,
                    enum MHD_RequestTerminationCode toe) {
  struct srv_daemon *d = cls;
  srv__req *r = *con_cls;
  if (!r)
    return;
  double dt = srv__now() - r->t0;
  int cut = !r->raw && toe != MHD_REQUEST_TERMINATED_COMPLETED_OK &&
            toe != MHD_REQUEST_TERMINATED_DAEMON_SHUTDOWN;
  int status = r->done && !cut ? r->status : 499;
  if (!r->done && toe == MHD_REQUEST_TERMINATED_WITH_ERROR)
    status = library_status(c, status);
  srv_metrics_observe(d->metrics, r->ep, status, dt);
  srv_metrics_in_flight(d->metrics, -1);
  if (r->batch)
    r->bytes = srv__batch_detach(r->batch);
  if (r->res)
    srv__results_detach(r->res);
  if (!d->cfg.quiet)
    access_log(d, r, status, dt);
  /* the next request on this connection has its own deadline */
  srv__receiving(d, r->cn, 1);
  if (r->cn && r->cn->req == r)
    r->cn->req = NULL;
  srv__held(d, r->key, -r->held);
  api_response_free(&r->ar);
  api_batch_free(r->ab);
  free(r->buf);
  free(r);
  *con_cls = NULL;
}
