/*
 * fuzz_http.c: a live stickslipd on arbitrary bytes.
 *
 * One daemon is started in the process (the same code as stickslipd, the
 * static library stickslipd_lib), with small compute limits.  Each input is
 * written, raw, to one end of a socketpair whose other end is handed to the
 * daemon as an accepted connection (srv_add_connection); the writing side
 * is then shut down and everything the daemon answers is read until it
 * closes.  Whatever the bytes, the daemon must not crash, leak or hang (an
 * answer not complete within 10 s aborts), and what it sends back, if
 * anything, must be HTTP/1.x responses.  Built as a libFuzzer target with
 * clang (-DSTICKSLIP_FUZZ=ON) and, with replay.c, as an ordinary test that
 * runs the stored corpus (tests/fuzz/http_corpus).  With FUZZ_HTTP_TCP set
 * in the environment each input comes instead over a loopback TCP
 * connection to the daemon's own listening socket, the path clients take.
 * With FUZZ_HTTP_GDB set, an answer still unfinished after 3.5 s makes the
 * harness print every thread's stack (gdb) before it waits out the 10 s.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <time.h>
#include <unistd.h>

#include "server.h"
#include "stickslip.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The job store's directory, removed at exit with its files. */
static char store_dir[] = "/tmp/stickslip-fuzz-XXXXXX";

static void remove_store(void) {
  static const char *const files[] = {"jobs.sqlite", "jobs.sqlite-wal",
                                      "jobs.sqlite-shm", "jobs.sqlite-journal"};
  char path[128];
  for (size_t i = 0; i < sizeof files / sizeof *files; i++) {
    snprintf(path, sizeof path, "%s/%s", store_dir, files[i]);
    unlink(path);
  }
  rmdir(store_dir);
}

static struct srv_daemon *daemon_once(void) {
  static struct srv_daemon *d;
  if (d)
    return d;
  srv_config cfg;
  memset(&cfg, 0, sizeof cfg);
  snprintf(cfg.bind, sizeof cfg.bind, "127.0.0.1");
  cfg.port = 0;
  api_limits_default(&cfg.lim);
  cfg.lim.max_body = 64 * 1024;
  cfg.lim.max_samples = 2000;
  cfg.lim.max_events = 20000;
  cfg.lim.max_event_list = 2000;
  cfg.lim.max_horizon = 1e4;
  cfg.lim.max_seconds = 0.2;
  cfg.lim.max_orbits = 4;
  cfg.max_conn = 64;
  cfg.per_ip = 64;
  cfg.timeout = 3;
  cfg.workers = 2;
  cfg.client_workers = 1;
  cfg.client_queue = 64;
  /* libmicrohttpd 0.9.75 keeps a connection whose peer half-closed in the
   * middle of a request line (say "PGE" then EOF) open; the daemon's
   * request deadline is what closes it, so it is short here */
  cfg.request_timeout = 0.3;
  cfg.drain = 1;
  cfg.quiet = 1;
  cfg.memory_mb = 64;
  cfg.stream_above = 4096; /* so that small answers stream too */
  /* jobs on a store of its own, so that Prefer: respond-async and the
   * /jobs resources are fuzzed too (one worker, a second of compute) */
  if (!mkdtemp(store_dir))
    abort();
  atexit(remove_store);
  snprintf(cfg.job_store, sizeof cfg.job_store, "sqlite:%s/jobs.sqlite",
           store_dir);
  cfg.job_workers = 1;
  cfg.job_max_seconds = 1;
  cfg.job_ttl = 3600;
  cfg.job_lease = 30;
  cfg.max_job_body = 64 * 1024;
  cfg.max_job_items = 64;
  ss_gsl_quiet();
  signal(SIGPIPE, SIG_IGN);
  if (!(d = srv_start(&cfg)))
    abort();
  return d;
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  struct srv_daemon *d = daemon_once();
  int sv[2] = {-1, -1};
  unsigned long started = srv_connections_started(d);
  if (getenv("FUZZ_HTTP_TCP")) {
    /* through the daemon's own listening socket, as a client comes */
    struct sockaddr_in a;
    memset(&a, 0, sizeof a);
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)srv_port(d));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if ((sv[0] = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0)) < 0 ||
        connect(sv[0], (struct sockaddr *)&a, sizeof a) != 0)
      abort();
  } else {
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, sv) != 0)
      abort();
    /* a local peer: libmicrohttpd then sets no TCP options on it */
    struct sockaddr_un peer;
    memset(&peer, 0, sizeof peer);
    peer.sun_family = AF_UNIX;
    if (srv_add_connection(d, sv[1], (struct sockaddr *)&peer, sizeof peer)) {
      close(sv[0]);
      return 0; /* the daemon refused it (and closed its end) */
    }
  }
  /* write the input while reading what comes back, so that neither side
   * blocks on a full buffer */
  size_t sent = 0, got = 0, cap = 1 << 16;
  char *buf = malloc(cap);
  int wr_open = 1, dumped = 0;
  double deadline = now() + 10;
  for (;;) {
    if (wr_open && sent == size) {
      shutdown(sv[0], SHUT_WR);
      wr_open = 0;
    }
    struct pollfd p = {sv[0], (short)(POLLIN | (wr_open ? POLLOUT : 0)), 0};
    int ms = (int)((deadline - now()) * 1e3);
    int look = !dumped && getenv("FUZZ_HTTP_GDB");
    if (look && now() > deadline - 6.5) {
      char cmd[160];
      snprintf(cmd, sizeof cmd,
               "gdb -p %d -batch -ex 'thread apply all bt 12' 1>&2 2>/dev/null",
               (int)getpid());
      fprintf(stderr, "fuzz_http: no end after 3.5 s; the threads:\n");
      if (system(cmd) != 0)
        fprintf(stderr, "fuzz_http: gdb failed\n");
      dumped = 1;
      continue;
    }
    int k = ms <= 0 ? 0 : poll(&p, 1, look && ms > 6500 ? ms - 6500 : ms);
    if ((k < 0 && errno == EINTR) || (k == 0 && look))
      continue;
    if (k <= 0) {
      /* which side lost it: libmicrohttpd never took the connection up
       * from its queue of added connections, or the daemon has it */
      fprintf(stderr,
              "fuzz_http: no end of the answer within 10 s (libmicrohttpd "
              "%s the connection)\n",
              srv_connections_started(d) > started ? "took up"
                                                   : "never took up");
      srv_conn_state st;
      int port = 0;
      if (sv[1] < 0) {
        struct sockaddr_in me;
        socklen_t ml = sizeof me;
        if (getsockname(sv[0], (struct sockaddr *)&me, &ml) == 0)
          port = ntohs(me.sin_port);
      }
      if (srv_connection_watched(d, sv[1], port, &st) == 0)
        fprintf(stderr,
                "fuzz_http: the monitor watches it: receiving %d, shut %d, "
                "age %.3f s, requests %d, suspended %d, resumed %d\n",
                st.receiving, st.shut, st.age, st.requests, st.suspended,
                st.resumed);
      else
        fprintf(stderr, "fuzz_http: the monitor does not watch it\n");
      abort();
    }
    if (wr_open && (p.revents & POLLOUT)) {
      ssize_t m = send(sv[0], data + sent, size - sent, MSG_NOSIGNAL);
      if (m > 0)
        sent += (size_t)m;
      else
        wr_open = 0; /* the daemon closed: no more to write */
    }
    if (p.revents & (POLLIN | POLLHUP | POLLERR)) {
      if (got + 4096 > cap)
        buf = realloc(buf, cap *= 2);
      ssize_t m = recv(sv[0], buf + got, cap - got, 0);
      if (m <= 0)
        break;
      got += (size_t)m;
    }
  }
  close(sv[0]);
  if (got && (got < 8 || memcmp(buf, "HTTP/1.", 7) != 0)) {
    fprintf(stderr, "fuzz_http: the answer is not HTTP: %.*s\n",
            (int)(got < 200 ? got : 200), buf);
    abort();
  }
  free(buf);
  return 0;
}
