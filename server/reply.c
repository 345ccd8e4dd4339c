/*
 * reply.c: the daemon's answers.  The headers every answer carries
 * (nosniff, X-Request-Id, CORS for the origins --cors-origin allows), gzip
 * for a client that accepts it, whole answers and streamed ones, the api's
 * problems with the request's id, and the memory budget that answers and
 * bodies count against.
 */
#define _GNU_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>

#include <zlib.h>

#include "internal.h"

/* gzip for a client that accepts it: answers from this size on (smaller ones
 * gain too little for the work) */
#define GZIP_MIN 1024

/* Whether Accept-Encoding names gzip with a quality above 0. */
int srv__accepts_gzip(struct MHD_Connection *c) {
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
  if (deflateInit2(&zs, SRV__GZIP_LEVEL, Z_DEFLATED, 15 + 16, 8,
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
void srv__common_headers(const srv__req *r, struct MHD_Response *resp) {
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
                            "Content-Type, X-Request-Id, Prefer");
    MHD_add_response_header(resp, "Access-Control-Max-Age", "600");
  } else {
    MHD_add_response_header(resp, "Access-Control-Expose-Headers",
                            "X-Request-Id, Retry-After, ETag, Location, "
                            "Preference-Applied");
  }
}

/* The origin of a browser's request, when --cors-origin allows it. */
void srv__cors_of(const struct srv_daemon *d, struct MHD_Connection *c,
                  srv__req *r) {
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

/* The Content-Security-Policy of a page.  The explorer: its own files
 * only, and calls to any daemon it is pointed at (?api=).  The user's
 * guide: mkdocs' theme runs inline scripts and styles of its own (the guide
 * is built from the source tree, never from a request), and nothing else. */
#define EXPLORER_POLICY                                                        \
  "default-src 'self'; connect-src 'self' http: https:; img-src 'self' "       \
  "data:; base-uri 'none'; form-action 'none'; frame-ancestors 'none'"
#define GUIDE_POLICY                                                           \
  "default-src 'self'; script-src 'self' 'unsafe-inline'; style-src 'self' "   \
  "'unsafe-inline'; img-src 'self' data:; base-uri 'none'; form-action "       \
  "'self'; frame-ancestors 'none'"

enum MHD_Result srv__send_body(struct MHD_Connection *c, srv__req *r,
                               int status, char *body, size_t len,
                               const char *ctype, int retry_after,
                               const char *allow, int close) {
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
  if (r->vary_accept)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_VARY, "Accept");
  if (gz)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_ENCODING, "gzip");
  srv__common_headers(r, resp);
  if (ctype && !strncmp(ctype, "text/html", 9))
    MHD_add_response_header(resp, "Content-Security-Policy",
                            r->doc ? GUIDE_POLICY : EXPLORER_POLICY);
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
  if (r->location[0] && status == 201) {
    /* a job made of the request (Prefer: respond-async, RFC 7240) */
    MHD_add_response_header(resp, MHD_HTTP_HEADER_LOCATION, r->location);
    MHD_add_response_header(resp, "Preference-Applied", "respond-async");
  }
  if (allow)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ALLOW, allow);
  if (r->accept_encoding)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ACCEPT_ENCODING,
                            r->accept_encoding);
  if (close)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONNECTION, "close");
  ok = MHD_queue_response(c, (unsigned)status, resp);
  MHD_destroy_response(resp);
  r->status = status;
  r->bytes = len;
  r->done = 1;
  return ok;
}

/* A streamed answer and the request it answers, whose byte count it keeps
 * (libmicrohttpd reads the stream only while the request is in progress;
 * it may free it after the request has completed). */
typedef struct sstream {
  api_stream *s;
  srv__req *r;
  /* gzip: the deflate state and the answer's text not yet deflated */
  int gz, eof, end;
  z_stream zs;
  char in[SRV__STREAM_CHUNK];
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
static enum MHD_Result send_stream(struct MHD_Connection *c, srv__req *r,
                                   api_response *ar) {
  sstream *st = calloc(1, sizeof *st);
  if (st && r->gzip && compressible(ar->content_type) &&
      deflateInit2(&st->zs, SRV__GZIP_LEVEL, Z_DEFLATED, 15 + 16, 8,
                   Z_DEFAULT_STRATEGY) == Z_OK) {
    st->gz = 1;
    if (r->d)
      srv__hold(r->d, r, SRV__GZIP_STATE);
  }
  struct MHD_Response *resp = st ? MHD_create_response_from_callback(
                                       MHD_SIZE_UNKNOWN, SRV__STREAM_CHUNK,
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
  srv__common_headers(r, resp);
  ok = MHD_queue_response(c, (unsigned)ar->status, resp);
  MHD_destroy_response(resp);
  r->status = ar->status;
  r->done = 1;
  return ok;
}

/* A problem's body with the request's id as a member "request_id" (an
 * extension member of RFC 9457), so that a client's report of it can be
 * found in the log. */
static void problem_with_id(const srv__req *r, api_response *ar) {
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

/* An answer of the api: a 503 always says when to come back, and a 413,
 * a 503 or a refused framing closes the connection.  What the answer holds
 * counts against the memory budget until the request completes. */
enum MHD_Result srv__send_api(struct MHD_Connection *c, srv__req *r,
                              api_response *ar, const char *allow) {
  int busy = ar->status == 503;
  problem_with_id(r, ar);
  if (r->d)
    srv__hold(r->d, r, (long)ar->held);
  if (ar->stream)
    return send_stream(c, r, ar);
  enum MHD_Result ok =
      srv__send_body(c, r, ar->status, ar->body, ar->len, ar->content_type,
                     busy, allow, busy || ar->status == 413 || r->close);
  ar->body = NULL;
  return ok;
}

enum MHD_Result srv__send_problem(struct MHD_Connection *c, srv__req *r,
                                  api_problem_kind kind, const char *detail,
                                  const char *limit, double limit_value,
                                  const char *allow) {
  api_response ar;
  api_problem(&ar, kind, detail, NULL, limit, limit_value);
  return srv__send_api(c, r, &ar, allow);
}

void srv__send_raw_problem(srv__req *r, api_problem_kind kind,
                           const char *detail, const char *limit,
                           double limit_value) {
  api_response ar;
  char head[512], date[64];
  struct tm tm;
  time_t now = time(NULL);
  api_problem(&ar, kind, detail, NULL, limit, limit_value);
  problem_with_id(r, &ar);
  gmtime_r(&now, &tm);
  strftime(date, sizeof date, "%a, %d %b %Y %H:%M:%S GMT", &tm);
  int n = snprintf(head, sizeof head,
                   "HTTP/1.1 %d %s\r\nDate: %s\r\nConnection: close\r\n"
                   "Content-Type: %s\r\nX-Content-Type-Options: nosniff\r\n"
                   "X-Request-Id: %s\r\nContent-Length: %zu\r\n\r\n",
                   ar.status, MHD_get_reason_phrase_for((unsigned)ar.status),
                   date, ar.content_type, r->rid, ar.len);
  int fd = r->cn ? r->cn->fd : -1;
  /* a fresh answer on a connection that sends nothing else: it fits the
   * socket's buffer */
  if (fd >= 0 && n > 0 && (size_t)n < sizeof head &&
      send(fd, head, (size_t)n, MSG_NOSIGNAL | MSG_DONTWAIT) == n &&
      send(fd, ar.body, ar.len, MSG_NOSIGNAL | MSG_DONTWAIT) == (ssize_t)ar.len)
    r->bytes = ar.len;
  if (fd >= 0)
    shutdown(fd, SHUT_WR);
  r->status = ar.status;
  r->done = r->raw = r->close = 1;
  api_response_free(&ar);
}

/* ---- the memory budget ---------------------------------------------------
 *
 * Bodies and answers in flight count against --memory-budget, and against
 * their client's share of it (the client key of the pool's queues).  A
 * client may start work while the budget is not spent and it holds less
 * than budget / (k + 1), k the clients holding some (itself included): a
 * client alone takes at most half, and with k clients at their shares one
 * share is still free for a newcomer, so that one address's connections
 * that never read their answers get the 503s themselves.  A client that
 * holds nothing is always under its share: every client may have an
 * answer, however large, while the budget is not spent.
 */

void srv__held(struct srv_daemon *d, const char *key, long bytes) {
  srv_metrics_held(d->metrics, bytes);
  srv__tally_add(d->held, key, bytes);
}

/* Count @a bytes against the memory budget for request @a r (negative to
 * give them back). */
void srv__hold(struct srv_daemon *d, srv__req *r, long bytes) {
  r->held += bytes;
  srv__held(d, r->key, bytes);
}

/* What client @a key holds, its share, and the clients that hold some. */
static long share_of(struct srv_daemon *d, const char *key, long *share,
                     unsigned *clients) {
  long mine = srv__tally_get(d->held, key, clients, NULL);
  *share = ((long)d->cfg.memory_mb << 20) / ((long)*clients + 1);
  return mine;
}

int srv__over_budget(struct srv_daemon *d, const char *key) {
  long share;
  unsigned clients;
  if (srv_metrics_held(d->metrics, 0) >= (long)d->cfg.memory_mb << 20)
    return 1;
  long mine = share_of(d, key, &share, &clients);
  return mine > 0 && mine >= share ? 2 : 0;
}

void srv__budget_problem(struct srv_daemon *d, const char *key,
                         api_response *ar) {
  char detail[200];
  long share;
  unsigned clients;
  srv_metrics_over_budget(d->metrics);
  long mine = share_of(d, key, &share, &clients);
  if (srv_metrics_held(d->metrics, 0) < (long)d->cfg.memory_mb << 20 &&
      mine > 0)
    snprintf(detail, sizeof detail,
             "this client's answers in flight hold %.1f MiB, its share of "
             "the memory budget of %zu MiB among %u clients is %.1f MiB; "
             "read them, or retry after a second",
             (double)mine / 1048576.0, d->cfg.memory_mb, clients,
             (double)share / 1048576.0);
  else
    snprintf(detail, sizeof detail,
             "the answers in flight hold %.1f MiB, the memory budget is %zu "
             "MiB; retry after a second",
             (double)srv_metrics_held(d->metrics, 0) / 1048576.0,
             d->cfg.memory_mb);
  api_problem(ar, API_P_OVERLOADED, detail, NULL, NULL, 0);
}
