/*
 * main.c: stickslipd's flags, environment and signals.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <jansson.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "server.h"
#include "stickslip.h"

static void usage(FILE *f) {
  api_limits l;
  api_limits_default(&l);
  fprintf(f,
          "usage: stickslipd [options]\n"
          "\n"
          "Serves the stick-slip orbit solver over HTTP/JSON: POST /orbit,\n"
          "/simulate, /stability; GET /health, /version, /openapi.json,\n"
          "/metrics.  Prints the URL it listens on to stderr when ready.\n"
          "\n"
          "  --bind ADDR               address to listen on (STICKSLIP_BIND;\n"
          "                            default 127.0.0.1; IPv6 allowed)\n"
          "  --port N                  port (STICKSLIP_PORT; default 8080;\n"
          "                            0 picks a free port)\n"
          "  --max-body BYTES          request body limit (%zu)\n"
          "  --max-samples N           samples in one response (%zu)\n"
          "  --max-events N            events computed by one /simulate (%zu)\n"
          "  --max-event-list N        events listed in one response (%zu)\n"
          "  --max-horizon T           t_end - t0, dimensionless (%g)\n"
          "  --max-seconds S           compute time of one request (%g)\n"
          "  --max-orbits N            orbits in one /orbit response (%d)\n"
          "  --max-depth N             JSON nesting depth (%d)\n"
          "  --workers N               computations at once (number of cores)\n"
          "  --queue-timeout S         wait for a compute slot before 503 (2)\n"
          "  --max-connections N       open connections (256)\n"
          "  --per-ip-connections N    open connections per client (64)\n"
          "  --connection-timeout S    idle connection timeout (10)\n"
          "  --drain S                 grace for requests in flight on\n"
          "                            SIGTERM/SIGINT (8)\n"
          "  --quiet                   no access log\n"
          "  --version                 print the version and exit\n"
          "  --help                    this text\n",
          l.max_body, l.max_samples, l.max_events, l.max_event_list,
          l.max_horizon, l.max_seconds, l.max_orbits, l.max_depth);
}

static int parse_ull(const char *flag, const char *s, unsigned long long lo,
                     unsigned long long hi, unsigned long long *out) {
  char *end;
  errno = 0;
  if (!s || !*s || *s == '-')
    goto bad;
  *out = strtoull(s, &end, 10);
  if (errno || *end || *out < lo || *out > hi)
    goto bad;
  return 0;
bad:
  fprintf(stderr, "stickslipd: %s needs a whole number in [%llu, %llu]\n", flag,
          lo, hi);
  return -1;
}

static int parse_dbl(const char *flag, const char *s, double lo, double hi,
                     double *out) {
  char *end;
  errno = 0;
  if (!s || !*s)
    goto bad;
  *out = strtod(s, &end);
  if (errno || *end || !(*out >= lo && *out <= hi))
    goto bad;
  return 0;
bad:
  fprintf(stderr, "stickslipd: %s needs a number in [%g, %g]\n", flag, lo, hi);
  return -1;
}

int main(int argc, char **argv) {
  srv_config cfg;
  unsigned long long u;
  const char *env;
  memset(&cfg, 0, sizeof cfg);
  snprintf(cfg.bind, sizeof cfg.bind, "127.0.0.1");
  cfg.port = 8080;
  api_limits_default(&cfg.lim);
  cfg.max_conn = 256;
  cfg.per_ip = 64;
  cfg.timeout = 10;
  long nc = sysconf(_SC_NPROCESSORS_ONLN);
  cfg.workers = nc > 0 ? (unsigned)nc : 1;
  cfg.queue_timeout = 2;
  cfg.drain = 8;
  if ((env = getenv("STICKSLIP_BIND")) && *env)
    snprintf(cfg.bind, sizeof cfg.bind, "%s", env);
  if ((env = getenv("STICKSLIP_PORT")) && *env) {
    if (parse_ull("STICKSLIP_PORT", env, 0, 65535, &u))
      return 2;
    cfg.port = (int)u;
  }
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    double x;
    int used = 1;
    if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      usage(stdout);
      return 0;
    } else if (!strcmp(a, "--version")) {
      printf("stickslipd %s\n", SS_VERSION);
      return 0;
    } else if (!strcmp(a, "--quiet")) {
      cfg.quiet = 1;
      used = 0;
    } else if (!strcmp(a, "--bind")) {
      if (!v || strlen(v) >= sizeof cfg.bind) {
        fprintf(stderr, "stickslipd: --bind needs an address\n");
        return 2;
      }
      snprintf(cfg.bind, sizeof cfg.bind, "%s", v);
    } else if (!strcmp(a, "--port")) {
      if (parse_ull(a, v, 0, 65535, &u))
        return 2;
      cfg.port = (int)u;
    } else if (!strcmp(a, "--max-body")) {
      if (parse_ull(a, v, 64, 1ULL << 30, &u))
        return 2;
      cfg.lim.max_body = (size_t)u;
    } else if (!strcmp(a, "--max-samples")) {
      if (parse_ull(a, v, 1, 100000000ULL, &u))
        return 2;
      cfg.lim.max_samples = (size_t)u;
    } else if (!strcmp(a, "--max-events")) {
      if (parse_ull(a, v, 1, 1000000000ULL, &u))
        return 2;
      cfg.lim.max_events = (size_t)u;
    } else if (!strcmp(a, "--max-event-list")) {
      if (parse_ull(a, v, 1, 100000000ULL, &u))
        return 2;
      cfg.lim.max_event_list = (size_t)u;
    } else if (!strcmp(a, "--max-horizon")) {
      if (parse_dbl(a, v, 1e-9, 1e15, &x))
        return 2;
      cfg.lim.max_horizon = x;
    } else if (!strcmp(a, "--max-seconds")) {
      if (parse_dbl(a, v, 1e-3, 3600, &x))
        return 2;
      cfg.lim.max_seconds = x;
    } else if (!strcmp(a, "--max-orbits")) {
      if (parse_ull(a, v, 1, 1024, &u))
        return 2;
      cfg.lim.max_orbits = (int)u;
    } else if (!strcmp(a, "--max-depth")) {
      if (parse_ull(a, v, 2, 2048, &u))
        return 2;
      cfg.lim.max_depth = (int)u;
    } else if (!strcmp(a, "--workers")) {
      if (parse_ull(a, v, 1, 1024, &u))
        return 2;
      cfg.workers = (unsigned)u;
    } else if (!strcmp(a, "--queue-timeout")) {
      if (parse_dbl(a, v, 0, 600, &x))
        return 2;
      cfg.queue_timeout = x;
    } else if (!strcmp(a, "--max-connections")) {
      if (parse_ull(a, v, 1, 65536, &u))
        return 2;
      cfg.max_conn = (unsigned)u;
    } else if (!strcmp(a, "--per-ip-connections")) {
      if (parse_ull(a, v, 1, 65536, &u))
        return 2;
      cfg.per_ip = (unsigned)u;
    } else if (!strcmp(a, "--connection-timeout")) {
      if (parse_ull(a, v, 1, 3600, &u))
        return 2;
      cfg.timeout = (unsigned)u;
    } else if (!strcmp(a, "--drain")) {
      if (parse_dbl(a, v, 0, 3600, &x))
        return 2;
      cfg.drain = x;
    } else {
      fprintf(stderr, "stickslipd: unknown option %s (see --help)\n", a);
      return 2;
    }
    i += used;
  }
  /* Before any thread exists: GSL must not abort, jansson's hash seed is
   * set once, and every thread inherits a mask that blocks the signals the
   * main thread waits for. */
  ss_gsl_quiet();
  json_object_seed(0);
  signal(SIGPIPE, SIG_IGN);
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  pthread_sigmask(SIG_BLOCK, &set, NULL);
  struct srv_daemon *d = srv_start(&cfg);
  if (!d)
    return 1;
  int sig = 0;
  sigwait(&set, &sig);
  fprintf(stderr, "stickslipd: signal %d, draining\n", sig);
  srv_stop(d);
  fprintf(stderr, "stickslipd: stopped\n");
  return 0;
}
