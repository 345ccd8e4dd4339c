/*
 * daemon.c: routing, body accumulation, admission control, logging.
 *
 * Threading: libmicrohttpd's thread-per-connection mode, the one mode in
 * which a callback may block; so a long computation holds only its own
 * connection's thread and a short request (/health) never waits behind it.
 * Computations are admitted through a counting semaphore of cfg->workers
 * slots; a request that cannot get a slot within cfg->queue_timeout is
 * answered 503 with Retry-After.  Each connection is bounded in memory
 * (MHD_OPTION_CONNECTION_MEMORY_LIMIT) and in idle time; bodies are bounded
 * by cfg->lim.max_body, refused with 413 from Content-Length when possible.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <netinet/in.h>
#include <semaphore.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <microhttpd.h>

#include "server.h"

/* A body that trickles in for longer than this is dropped (slow loris). */
#define BODY_SECONDS 10.0

struct srv_daemon {
  struct MHD_Daemon *mhd;
  srv_config cfg;
  sem_t slots;
  srv_metrics *metrics;
  char transport[48];
  atomic_int draining;
  double started;
};

typedef struct req {
  size_t ep; /* endpoint index; api_endpoint_count() until routed */
  int is_post;
  int status;
  int done; /* a response was queued */
  char *buf;
  size_t len, cap;
  int too_big;
  double t0;
  char method[8];
  char path[96];
  /* An answer decided on the first call, sent on a later one: libmicrohttpd
   * handles a response queued during the first call of a request far more
   * slowly (about 200 us each, serialised), so only the 413 that must stop a
   * large body is queued that early. */
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

static enum MHD_Result send_body(struct MHD_Connection *c, req *r, int status,
                                 char *body, size_t len, const char *ctype,
                                 int must_free, int retry_after,
                                 const char *allow, int close) {
  struct MHD_Response *resp = MHD_create_response_from_buffer(
      len, body, must_free ? MHD_RESPMEM_MUST_FREE : MHD_RESPMEM_PERSISTENT);
  enum MHD_Result ok;
  if (!resp) {
    if (must_free)
      free(body);
    return MHD_NO;
  }
  MHD_add_response_header(resp, MHD_HTTP_HEADER_CONTENT_TYPE, ctype);
  MHD_add_response_header(resp, "X-Content-Type-Options", "nosniff");
  if (retry_after)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_RETRY_AFTER, "1");
  if (allow)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_ALLOW, allow);
  if (close)
    MHD_add_response_header(resp, MHD_HTTP_HEADER_CONNECTION, "close");
  ok = MHD_queue_response(c, (unsigned)status, resp);
  MHD_destroy_response(resp);
  r->status = status;
  r->done = 1;
  return ok;
}

/* An answer of the api: a 503 always says when to come back, and a 413 or
 * 503 closes the connection. */
static enum MHD_Result send_api(struct MHD_Connection *c, req *r,
                                api_response *ar, const char *allow) {
  int busy = ar->status == 503;
  enum MHD_Result ok =
      send_body(c, r, ar->status, ar->body, ar->len, ar->content_type, 1, busy,
                allow, busy || ar->status == 413);
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

/* One request to the api, with what the daemon knows of itself. */
static void handle(struct srv_daemon *d, req *r, api_response *ar) {
  api_server_info info = {now() - d->started,
                          srv_metrics_in_flight(d->metrics, 0), d->transport,
                          metrics_text, d};
  api_handle(r->ep, r->buf ? r->buf : "", r->len, &d->cfg.lim, &info, ar);
  if (ar->status >= 500 && ar->status != 503)
    fprintf(stderr, "stickslipd: %s %s answered %d: %.200s\n", r->method,
            r->path, ar->status, ar->body ? ar->body : "");
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

static enum MHD_Result compute(struct srv_daemon *d, struct MHD_Connection *c,
                               req *r) {
  struct timespec dl;
  api_response ar;
  clock_gettime(CLOCK_REALTIME, &dl);
  double w = d->cfg.queue_timeout;
  dl.tv_sec += (time_t)w;
  dl.tv_nsec += (long)((w - floor(w)) * 1e9);
  if (dl.tv_nsec >= 1000000000L) {
    dl.tv_sec++;
    dl.tv_nsec -= 1000000000L;
  }
  int got;
  while ((got = sem_timedwait(&d->slots, &dl)) != 0 && errno == EINTR)
    ;
  if (got != 0) {
    srv_metrics_busy(d->metrics);
    return send_problem(c, r, API_P_OVERLOADED,
                        "every compute slot stayed busy; retry after a second",
                        NULL, 0, NULL);
  }
  handle(d, r, &ar);
  sem_post(&d->slots);
  return send_api(c, r, &ar, NULL);
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

/* The first call of a request: its headers are in.  Route it, and refuse
 * now what can be refused from the headers alone. */
static enum MHD_Result admit(struct srv_daemon *d, struct MHD_Connection *c,
                             req *r, const char *url, const char *method) {
  size_t ep;
  r->t0 = now();
  r->ep = api_endpoint_count();
  snprintf(r->method, sizeof r->method, "%s", method);
  snprintf(r->path, sizeof r->path, "%s", url);
  srv_metrics_in_flight(d->metrics, +1);
  if (atomic_load(&d->draining))
    return defer(r, API_P_SHUTTING_DOWN, "the server is shutting down", NULL);
  int route = api_route(method, url, &ep);
  if (route == 404)
    return defer(r, API_P_NOT_FOUND, "no such resource; see /openapi.json",
                 NULL);
  const api_endpoint *row = api_endpoint_at(ep);
  r->ep = ep;
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
  if (now() - r->t0 > BODY_SECONDS)
    return MHD_NO;
  if (r->too_big || r->len + n > d->cfg.lim.max_body) {
    r->too_big = 1;
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
  return MHD_YES;
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
  if (r->done || r->p_status) {
    /* an answer is decided: discard whatever body still comes */
    if (*upload_data_size || r->done) {
      *upload_data_size = 0;
      return MHD_YES;
    }
    return send_problem(c, r, r->p_kind, r->p_detail, NULL, 0, r->p_allow);
  }
  if (*upload_data_size) {
    size_t n = *upload_data_size;
    *upload_data_size = 0;
    return take_body(d, r, upload_data, n);
  }
  if (r->too_big)
    return too_large(d, c, r);
  if (!r->is_post) {
    api_response ar;
    handle(d, r, &ar);
    return send_api(c, r, &ar, NULL);
  }
  return compute(d, c, r);
}

static void completed(void *cls, struct MHD_Connection *c, void **con_cls,
                      enum MHD_RequestTerminationCode toe) {
  struct srv_daemon *d = cls;
  req *r = *con_cls;
  (void)c;
  if (!r)
    return;
  double dt = now() - r->t0;
  int status = r->done ? r->status : 499; /* 499: client went away */
  (void)toe;
  srv_metrics_observe(d->metrics, r->ep, status, dt);
  srv_metrics_in_flight(d->metrics, -1);
  if (!d->cfg.quiet)
    fprintf(stderr, "%s %s %d %ld\n", r->method, r->path, status,
            (long)(dt * 1e6));
  free(r->buf);
  free(r);
  *con_cls = NULL;
}

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

static void daemon_free(struct srv_daemon *d) {
  srv_metrics_free(d->metrics);
  free(d);
}

struct srv_daemon *srv_start(const srv_config *cfg) {
  struct srv_daemon *d = calloc(1, sizeof *d);
  struct sockaddr_storage ss;
  unsigned flags = MHD_USE_INTERNAL_POLLING_THREAD |
                   MHD_USE_THREAD_PER_CONNECTION | MHD_USE_AUTO | MHD_USE_ITC |
                   MHD_USE_ERROR_LOG;
  if (!d || !(d->metrics = srv_metrics_new())) {
    free(d);
    return NULL;
  }
  d->cfg = *cfg;
  d->started = now();
  snprintf(d->transport, sizeof d->transport, "%s", MHD_get_version());
  if (listen_address(cfg, &ss, &flags)) {
    fprintf(stderr, "stickslipd: --bind %s is not an IPv4 or IPv6 address\n",
            cfg->bind);
    daemon_free(d);
    return NULL;
  }
  if (sem_init(&d->slots, 0, cfg->workers) != 0) {
    daemon_free(d);
    return NULL;
  }
  d->mhd = MHD_start_daemon(
      flags, (uint16_t)cfg->port, NULL, NULL, handler, d, MHD_OPTION_SOCK_ADDR,
      (struct sockaddr *)&ss, MHD_OPTION_CONNECTION_LIMIT, cfg->max_conn,
      MHD_OPTION_PER_IP_CONNECTION_LIMIT, cfg->per_ip,
      MHD_OPTION_CONNECTION_TIMEOUT, cfg->timeout,
      MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)65536,
      MHD_OPTION_STRICT_FOR_CLIENT, (int)1, MHD_OPTION_NOTIFY_COMPLETED,
      completed, d, MHD_OPTION_END);
  if (!d->mhd) {
    fprintf(stderr, "stickslipd: cannot listen on %s port %d: %s\n", cfg->bind,
            cfg->port, strerror(errno));
    sem_destroy(&d->slots);
    daemon_free(d);
    return NULL;
  }
  int port = bound_port(d->mhd, cfg->port);
  if (strchr(cfg->bind, ':'))
    fprintf(stderr, "stickslipd listening on http://[%s]:%d\n", cfg->bind,
            port);
  else
    fprintf(stderr, "stickslipd listening on http://%s:%d\n", cfg->bind, port);
  fflush(stderr);
  return d;
}

void srv_stop(struct srv_daemon *d) {
  if (!d)
    return;
  atomic_store(&d->draining, 1);
  MHD_socket fd = MHD_quiesce_daemon(d->mhd);
  double until = now() + d->cfg.drain;
  while (srv_metrics_in_flight(d->metrics, 0) > 0 && now() < until) {
    struct timespec ts = {0, 10 * 1000 * 1000};
    nanosleep(&ts, NULL);
  }
  MHD_stop_daemon(d->mhd);
  if (fd != MHD_INVALID_SOCKET)
    close(fd);
  sem_destroy(&d->slots);
  daemon_free(d);
}
