/*
 * daemon.c: the daemon's start and stop: listening, descriptors, the
 * threads, and what the daemon tells the api about itself.
 *
 * Sockets.  One internal polling thread with epoll
 * (MHD_USE_EPOLL_INTERNAL_THREAD): an idle or slow connection costs a
 * socket, not a thread.  libmicrohttpd's own loop, not one of the daemon's
 * calling MHD_run: driven from outside, 0.9.75 keeps a connection whose
 * read buffer is full and unprocessable (a chunk line longer than the
 * buffer) on its list of ready connections, so its loop turns without
 * waiting, at a full core, until that connection closes; and from outside
 * the library such a connection cannot be told from an idle one once its
 * socket holds no more bytes.  The internal loop answers it 500 instead,
 * and wire.c refuses such a line with 413 before it fills the buffer
 * (docs/howto/limits.md).  Its callbacks are request.c's (a request) and
 * monitor.c's (a connection); computations run in the pool (pool.c); a
 * monitor thread (monitor.c) watches the connections; jobs have their own
 * runners and ticker (jobs.c).
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "internal.h"

double srv__now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static char *metrics_text(void *cls) {
  struct srv_daemon *d = cls;
  srv_metrics_pool(d->metrics, d->pool);
  if (d->jobs)
    srv__jobs_metrics(d->jobs);
  return srv_metrics_render(d->metrics);
}

static int job_cancelled(void *cls) {
  return atomic_load(&((srv_job *)cls)->cancel);
}

/* A /map's or a /basins' threads: its own worker and what it may borrow. */
static unsigned job_threads(void *cls, unsigned want) {
  return 1 + srv_pool_borrow(cls, want > 1 ? want - 1 : 0);
}

api_server_info srv__server_info(struct srv_daemon *d, srv_job *job) {
  api_server_info info = {srv__now() - d->started,
                          srv_metrics_in_flight(d->metrics, 0),
                          d->transport,
                          metrics_text,
                          d,
                          job_cancelled,
                          job,
                          d->cfg.stream_above,
                          job_threads,
                          job};
  return info;
}

/* ---- start and stop ------------------------------------------------------ */

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

/* The one line that says the port is taken, and the way out. */
static void say_port_taken(const srv_config *cfg) {
  fprintf(stderr,
          "stickslipd: port %d on %s is taken by another program: choose "
          "another with --port N (or STICKSLIP_PORT=N), or --port 0 for any "
          "free one\n",
          cfg->port, cfg->bind);
}

/* Whether the address of @a ss can be bound, tried as libmicrohttpd binds
 * it (SO_REUSEADDR: a socket of a closed daemon in TIME_WAIT does not
 * count): 0, or -1 with errno EADDRINUSE when another socket listens on it,
 * so that this is said in one line, before libmicrohttpd would say it in
 * its own words.  Any other error is left to libmicrohttpd to meet. */
static int port_free(const struct sockaddr_storage *ss) {
  int fd = socket(ss->ss_family, SOCK_STREAM | SOCK_CLOEXEC, 0), on = 1, rc = 0;
  socklen_t len = ss->ss_family == AF_INET6 ? sizeof(struct sockaddr_in6)
                                            : sizeof(struct sockaddr_in);
  if (fd < 0)
    return 0;
  setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  if (ss->ss_family == AF_INET6)
    setsockopt(fd, IPPROTO_IPV6, IPV6_V6ONLY, &on, sizeof on);
  if (bind(fd, (const struct sockaddr *)ss, len) != 0 && errno == EADDRINUSE)
    rc = -1;
  close(fd);
  errno = rc ? EADDRINUSE : errno;
  return rc;
}

/* Descriptors beside the connections': listening, epoll, the job store,
 * logs. */
#define SPARE_FDS 64

/* Enough descriptors for every connection the flags allow, as far as the
 * hard limit lets: the soft limit after, when it is still too few, else 0. */
static unsigned long long raise_fd_limit(unsigned max_conn) {
  struct rlimit rl;
  if (getrlimit(RLIMIT_NOFILE, &rl) != 0)
    return 0;
  rlim_t want = (rlim_t)max_conn + SPARE_FDS;
  if (rl.rlim_cur < want) {
    struct rlimit raised = rl;
    raised.rlim_cur = rl.rlim_max < want ? rl.rlim_max : want;
    if (setrlimit(RLIMIT_NOFILE, &raised) == 0)
      rl = raised;
  }
  return rl.rlim_cur < want ? (unsigned long long)rl.rlim_cur : 0;
}

static void daemon_free(struct srv_daemon *d) {
  if (d->monitor_running) {
    atomic_store(&d->monitor_stop, 1);
    pthread_join(d->monitor, NULL);
  }
  srv__jobs_free(d->jobs);
  srv_pool_free(d->pool);
  srv_metrics_free(d->metrics);
  srv__tally_free(d->held);
  srv__tally_free(d->conns);
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
  d->started = srv__now();
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
  /* the jobs waiting are counted by the rows of the metrics */
  srv_pool_cfg pc = {cfg->workers, cfg->client_workers, cfg->client_queue,
                     (unsigned)srv_metrics_jobs_row() + 1};
  if (!(d->metrics = srv_metrics_new()) || !(d->pool = srv_pool_new(&pc)) ||
      !(d->held = srv__tally_new()) || !(d->conns = srv__tally_new())) {
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
  if (cfg->port && port_free(&ss)) {
    say_port_taken(cfg);
    daemon_free(d);
    errno = EADDRINUSE;
    return NULL;
  }
  unsigned long long fds = raise_fd_limit(cfg->max_conn);
  /* the limits by address are srv__accept's (libmicrohttpd's own per-IP
   * limit knows no trusted proxy and no reserve).  Not libmicrohttpd's
   * strict mode: 0.9.75 answers a request without Host
   * there with its own page, whose header block it writes twice; request.c
   * refuses that, and a space in the target (srv__target), itself */
  /* jobs before the first request: a Prefer: respond-async that came
   * before them would be answered synchronously */
  if (!cfg->no_jobs)
    d->jobs = srv__jobs_start(d);
  d->mhd = MHD_start_daemon(
      flags, (uint16_t)cfg->port, srv__accept, d, srv__handler, d,
      MHD_OPTION_SOCK_ADDR, (struct sockaddr *)&ss, MHD_OPTION_CONNECTION_LIMIT,
      cfg->max_conn, MHD_OPTION_CONNECTION_TIMEOUT, cfg->timeout,
      MHD_OPTION_CONNECTION_MEMORY_LIMIT, (size_t)SRV__CONN_MEMORY,
      MHD_OPTION_STRICT_FOR_CLIENT, (int)0, MHD_OPTION_NOTIFY_COMPLETED,
      srv__completed, d, MHD_OPTION_NOTIFY_CONNECTION, srv__connection, d,
      MHD_OPTION_URI_LOG_CALLBACK, srv__target, d, MHD_OPTION_END);
  if (!d->mhd) {
    int err = errno;
    if (err == EADDRINUSE) /* taken since port_free looked */
      say_port_taken(cfg);
    else
      fprintf(stderr, "stickslipd: cannot listen on %s port %d: %s\n",
              cfg->bind, cfg->port, strerror(err));
    daemon_free(d);
    errno = err;
    return NULL;
  }
  if (pthread_create(&d->monitor, NULL, srv__monitor, d) == 0)
    d->monitor_running = 1;
  int port = d->port = bound_port(d->mhd, cfg->port);
  snprintf(d->url, sizeof d->url,
           strchr(cfg->bind, ':') ? "http://[%s]:%d" : "http://%s:%d",
           cfg->bind, port);
  fprintf(stderr, "stickslipd listening on %s\n", d->url);
  /* after the line that tells the URL, which a supervisor reads first */
  if (!cfg->no_jobs && !d->jobs)
    fprintf(stderr, "stickslipd: out of memory for jobs: none are kept\n");
  if (fds)
    fprintf(stderr,
            "stickslipd: the descriptor limit is %llu, too few for "
            "--max-connections %u (%u wanted): raise the hard limit "
            "(ulimit -Hn, LimitNOFILE=) or lower --max-connections\n",
            fds, cfg->max_conn, cfg->max_conn + SPARE_FDS);
  srv__jobs_announce(d->jobs);
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

const char *srv_url(struct srv_daemon *d) { return d->url; }

static void wait_in_flight(struct srv_daemon *d, double until) {
  struct timespec ts = {0, 10 * 1000 * 1000};
  while (srv_metrics_in_flight(d->metrics, 0) > 0 && srv__now() < until)
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
  /* the runners stop between chunks: one computing is cancelled, its lease
   * lapses, and the chunk is left to the store */
  srv__jobs_stop(d->jobs);
  double until = srv__now() + d->cfg.drain;
  if (!srv_pool_wait_idle(d->pool, d->cfg.drain)) {
    srv_pool_cancel_all(d->pool);
    srv_pool_wait_idle(d->pool, 5);
  }
  wait_in_flight(d, until > srv__now() + 1 ? until : srv__now() + 1);
  atomic_store(&d->monitor_stop, 1);
  if (d->monitor_running)
    pthread_join(d->monitor, NULL);
  d->monitor_running = 0;
  MHD_stop_daemon(d->mhd);
  daemon_free(d);
}
