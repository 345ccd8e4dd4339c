/*
 * main.c: stickslipd's flags, environment and signals.
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <errno.h>
#include <netdb.h>
#include <jansson.h>
#include <malloc.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include "notify.h"
#include "server.h"
#include "stickslip.h"

/* The numeric flags: each sets one field of srv_config, within a range. */
typedef enum flag_type { F_SIZE, F_INT, F_UNSIGNED, F_DOUBLE } flag_type;

typedef struct flag {
  const char *name;
  flag_type type;
  double lo, hi;
  size_t off;
  const char *help;
} flag;

#define CFG(m) offsetof(srv_config, m)
static const flag FLAGS[] = {
    {"--port", F_INT, 0, 65535, CFG(port),
     "port (STICKSLIP_PORT; 0 picks a free port)"},
    {"--max-body", F_SIZE, 64, 1 << 30, CFG(lim.max_body),
     "request body limit, bytes"},
    {"--max-samples", F_SIZE, 1, 1e8, CFG(lim.max_samples),
     "samples in one response"},
    {"--max-events", F_SIZE, 1, 1e9, CFG(lim.max_events),
     "events computed by one /simulate"},
    {"--max-event-list", F_SIZE, 1, 1e8, CFG(lim.max_event_list),
     "events listed in one response"},
    {"--max-horizon", F_DOUBLE, 1e-9, 1e15, CFG(lim.max_horizon),
     "t_end - t0, dimensionless"},
    {"--max-seconds", F_DOUBLE, 1e-3, 3600, CFG(lim.max_seconds),
     "compute time of one request, seconds"},
    {"--max-orbits", F_INT, 1, 1024, CFG(lim.max_orbits),
     "orbits in one /orbit response"},
    {"--max-depth", F_INT, 2, 2048, CFG(lim.max_depth), "JSON nesting depth"},
    {"--max-batch-items", F_SIZE, 1, 1e7, CFG(lim.max_batch_items),
     "requests in one /batch"},
    {"--max-points", F_SIZE, 2, 1e6, CFG(lim.max_points),
     "points of one /continue family"},
    {"--max-map-cells", F_SIZE, 1, 1e7, CFG(lim.max_map_cells),
     "cells of one /map"},
    {"--max-basin-cells", F_SIZE, 1, 1e8, CFG(lim.max_basin_cells),
     "cells of one /basins slice"},
    {"--map-threads", F_UNSIGNED, 1, 1024, CFG(lim.map_threads),
     "threads of one /map or /basins at most, of its client's workers "
     "(default: workers)"},
    {"--batch-parallel", F_UNSIGNED, 1, 1024, CFG(batch_parallel),
     "items of one /batch in flight at once (default: workers)"},
    {"--workers", F_UNSIGNED, 1, 1024, CFG(workers),
     "computations at once (default: the number of cores)"},
    {"--client-workers", F_UNSIGNED, 1, 1024, CFG(client_workers),
     "computations of one client at once, /map's and /basins' threads "
     "included (default: workers - 1, at least 1)"},
    {"--client-queue", F_UNSIGNED, 0, 1 << 20, CFG(client_queue),
     "computations of one client waiting; more get 503 at once"},
    {"--request-timeout", F_DOUBLE, 0.1, 3600, CFG(request_timeout),
     "deadline for a request's headers and body, seconds"},
    {"--max-connections", F_UNSIGNED, 1, 65536, CFG(max_conn),
     "open connections"},
    {"--per-ip-connections", F_UNSIGNED, 1, 65536, CFG(per_ip),
     "open connections per client address (a --trusted-proxy: no limit)"},
    {"--reserved-connections", F_UNSIGNED, 0, 65536, CFG(reserved),
     "the last connections, taken only by an address holding fewer than 8"},
    {"--connection-timeout", F_UNSIGNED, 1, 3600, CFG(timeout),
     "idle connection timeout, seconds"},
    {"--drain", F_DOUBLE, 0, 3600, CFG(drain),
     "grace for requests in flight on SIGTERM/SIGINT, seconds"},
    {"--memory-budget", F_SIZE, 1, 1 << 20, CFG(memory_mb),
     "MiB that request bodies and answers in flight may hold; new work "
     "over it gets 503, and so does a client's over its share: budget / "
     "(k + 1), k clients holding some"},
    {"--job-workers", F_UNSIGNED, 0, 1024, CFG(job_workers),
     "threads computing chunks of jobs, beside --workers (0: this replica "
     "computes none)"},
    {"--job-max-seconds", F_DOUBLE, 1e-3, 1e8, CFG(job_max_seconds),
     "compute time of one job, from its start, seconds"},
    {"--job-lease", F_DOUBLE, 0.5, 3600, CFG(job_lease),
     "seconds a replica's claim of a chunk holds unless renewed (every "
     "third of it): how long a chunk of a replica that died waits"},
    {"--job-ttl", F_DOUBLE, 1, 1e10, CFG(job_ttl),
     "seconds a finished job is kept after it finished"},
    {"--max-job-body", F_SIZE, 64, 1e12, CFG(max_job_body),
     "request body limit of a job (Prefer: respond-async), bytes; it is "
     "held against --memory-budget while it comes"},
    {"--max-job-items", F_SIZE, 1, 1e9, CFG(max_job_items),
     "requests in one /batch job (a synchronous /batch takes "
     "--max-batch-items)"},
};
#define N_FLAGS (sizeof FLAGS / sizeof FLAGS[0])

static double get_value(const srv_config *cfg, const flag *f) {
  const char *p = (const char *)cfg + f->off;
  switch (f->type) {
  case F_SIZE:
    return (double)*(const size_t *)p;
  case F_INT:
    return *(const int *)p;
  case F_UNSIGNED:
    return *(const unsigned *)p;
  case F_DOUBLE:
    return *(const double *)p;
  }
  return 0;
}

static void set_value(srv_config *cfg, const flag *f, double v) {
  char *p = (char *)cfg + f->off;
  switch (f->type) {
  case F_SIZE:
    *(size_t *)p = (size_t)v;
    break;
  case F_INT:
    *(int *)p = (int)v;
    break;
  case F_UNSIGNED:
    *(unsigned *)p = (unsigned)v;
    break;
  case F_DOUBLE:
    *(double *)p = v;
    break;
  }
}

/* The other options, each parsed by configure() below: name, argument
 * (NULL: none), what it does.  --help prints these and FLAGS. */
#define STR_(x) #x
#define STR(x) STR_(x)
static const struct {
  const char *name, *arg, *help;
} OPTIONS[] = {
    {"--trusted-proxy", "ADDR",
     "a proxy whose X-Forwarded-For names the client (repeatable, up to " STR(
         SRV_MAX_PROXIES) ")"},
    {"--cors-origin", "ORIGIN",
     "an origin (http://host:port, or * for any) whose pages may call the "
     "daemon from a browser (repeatable, up to " STR(
         SRV_MAX_ORIGINS) "; none)"},
    {"--job-store", "URI",
     "the store of jobs: sqlite:PATH, or postgresql://... shared by "
     "replicas (sqlite:<state-dir>/jobs.sqlite); the daemon serves without "
     "it, jobs get 503"},
    {"--state-dir", "DIR",
     "where the default store is kept ($STATE_DIRECTORY, else "
     "./stickslip-state)"},
    {"--no-jobs", NULL,
     "no store: Prefer: respond-async is ignored, /jobs is 404"},
    {"--log-format", "json|plain",
     "the access log's lines: JSON (time, request_id, client, method, path, "
     "status, bytes, us) or plain (json)"},
    {"--quiet", NULL, "no access log"},
    {"--health-check", NULL,
     "serve nothing: GET /health of the daemon these options (and the "
     "environment) name, within 3 s; exit 0 when it answers 200, 1 "
     "otherwise (a container's HEALTHCHECK)"},
    {"--version", NULL, "print the version and exit"},
    {"--help", NULL, "this text"},
};
#define N_OPTIONS (sizeof OPTIONS / sizeof OPTIONS[0])

/* One option of --help: "  NAME ARG" in 26 columns, then @a help from
 * column 28, wrapped at 79 (on the next line when NAME ARG is longer). */
static void usage_line(FILE *f, const char *name, const char *arg,
                       const char *help) {
  enum { COL = 28, ROOM = 79 - COL };
  char head[64];
  snprintf(head, sizeof head, "%s%s%s", name, arg ? " " : "", arg ? arg : "");
  int first = fprintf(f, "  %-25s ", head) <= COL;
  while (*help) {
    size_t n = strlen(help);
    if (n > ROOM) { /* up to the last space that fits, or the first after */
      for (n = ROOM; n > 0 && help[n] != ' '; n--)
        ;
      if (n == 0)
        n = strcspn(help, " ");
    }
    if (!first)
      fprintf(f, "\n%*s", COL, "");
    fwrite(help, 1, n, f);
    help += n;
    help += *help == ' ';
    first = 0;
  }
  fputc('\n', f);
}

static void usage(FILE *f, const srv_config *defaults) {
  fprintf(f, "usage: stickslipd [options]\n\n"
             "Serves the stick-slip orbit solver over HTTP/JSON:\n");
  for (size_t i = 0; i < api_endpoint_count(); i++)
    fprintf(f, "  %-5s %s\n", api_endpoint_at(i)->method,
            api_endpoint_at(i)->path);
  fprintf(f, "Prints the URL it listens on to stderr when ready, and tells "
             "systemd READY=1\n(NOTIFY_SOCKET).\n\n");
  usage_line(f, "--bind", "ADDR",
             "address to listen on (STICKSLIP_BIND; default 127.0.0.1; IPv6 "
             "allowed)");
  for (size_t i = 0; i < N_FLAGS; i++) {
    char help[512];
    double v = get_value(defaults, &FLAGS[i]);
    /* a default outside the flag's range is one made at the start (the
     * workers'), which the flag's text names */
    if (v >= FLAGS[i].lo && v <= FLAGS[i].hi)
      snprintf(help, sizeof help, "%s (%.10g)", FLAGS[i].help, v);
    else
      snprintf(help, sizeof help, "%s", FLAGS[i].help);
    usage_line(f, FLAGS[i].name, FLAGS[i].type == F_DOUBLE ? "X" : "N", help);
  }
  for (size_t i = 0; i < N_OPTIONS; i++)
    usage_line(f, OPTIONS[i].name, OPTIONS[i].arg, OPTIONS[i].help);
  fprintf(
      f, "\nEvery option but --health-check, --version and --help can also be\n"
         "set in the environment as STICKSLIP_ and its name in capitals with\n"
         "underscores (STICKSLIP_MAX_SECONDS=30, STICKSLIP_QUIET=1,\n"
         "STICKSLIP_TRUSTED_PROXY=ADDR[,ADDR...],\n"
         "STICKSLIP_CORS_ORIGIN=ORIGIN[,ORIGIN...]); the command line wins.\n"
         "Exit status: 0 after SIGTERM or SIGINT, --help, --version; 1 when "
         "it cannot\nstart; 2 for a bad option; 3 when its port is taken.\n");
}

/* The value of flag @a f from the text @a s: a number within its range,
 * whole unless the flag takes a real. */
static int parse(const flag *f, const char *s, double *out) {
  char *end;
  errno = 0;
  if (s && *s && !(f->type != F_DOUBLE && *s == '-')) {
    *out =
        f->type == F_DOUBLE ? strtod(s, &end) : (double)strtoull(s, &end, 10);
    if (!errno && !*end && *out >= f->lo && *out <= f->hi)
      return 0;
  }
  fprintf(stderr, "stickslipd: %s needs %s in [%g, %g]\n", f->name,
          f->type == F_DOUBLE ? "a number" : "a whole number", f->lo, f->hi);
  return -1;
}

static void defaults(srv_config *cfg) {
  memset(cfg, 0, sizeof *cfg);
  snprintf(cfg->bind, sizeof cfg->bind, "127.0.0.1");
  cfg->port = 8080;
  api_limits_default(&cfg->lim);
  cfg->lim.map_threads = 0; /* the workers, once their number is known */
  cfg->max_conn = 2048;
  cfg->per_ip = 256;
  cfg->reserved = 256;
  cfg->timeout = 10;
  long nc = sysconf(_SC_NPROCESSORS_ONLN);
  cfg->workers = nc > 0 ? (unsigned)nc : 1;
  cfg->client_queue = 64;
  cfg->request_timeout = 10;
  cfg->memory_mb = 256;
  cfg->stream_above = 64 * 1024;
  /* longer than a computation may take, so that the requests in flight at
   * a shutdown get their answers */
  cfg->drain = 15;
  cfg->job_workers = 1;
  cfg->job_max_seconds = 86400;
  cfg->job_ttl = 7 * 86400;
  cfg->job_lease = 30;
  cfg->max_job_body = (size_t)256 << 20;
  cfg->max_job_items = 1000000;
}

/* The environment variable of option @a name ("--max-seconds" ->
 * "STICKSLIP_MAX_SECONDS") into @a out. */
static void env_name(const char *name, char *out, size_t n) {
  size_t k = (size_t)snprintf(out, n, "STICKSLIP_");
  for (const char *c = name + 2; *c && k + 1 < n; c++)
    out[k++] = *c == '-' ? '_' : (char)(*c >= 'a' && *c <= 'z' ? *c - 32 : *c);
  out[k] = 0;
}

static int set_log_format(srv_config *cfg, const char *v) {
  if (v && !strcmp(v, "json"))
    cfg->log_plain = 0;
  else if (v && !strcmp(v, "plain"))
    cfg->log_plain = 1;
  else {
    fprintf(stderr, "stickslipd: --log-format is json or plain\n");
    return -1;
  }
  return 0;
}

static int add_proxy(srv_config *cfg, const char *v) {
  if (cfg->n_trusted == SRV_MAX_PROXIES) {
    fprintf(stderr, "stickslipd: at most %d --trusted-proxy\n",
            SRV_MAX_PROXIES);
    return -1;
  }
  /* kept as the peer's address is written, so that they compare */
  if (!v || srv_address_text(v, cfg->trusted[cfg->n_trusted],
                             sizeof cfg->trusted[0])) {
    fprintf(stderr, "stickslipd: --trusted-proxy needs an IPv4 or IPv6 "
                    "address\n");
    return -1;
  }
  cfg->n_trusted++;
  return 0;
}

/* An origin as browsers send it: scheme://host[:port] with no path, or *. */
static int add_origin(srv_config *cfg, const char *v) {
  if (cfg->n_origins == SRV_MAX_ORIGINS) {
    fprintf(stderr, "stickslipd: at most %d --cors-origin\n", SRV_MAX_ORIGINS);
    return -1;
  }
  const char *host = v ? strstr(v, "://") : NULL;
  int ok = v && strlen(v) < sizeof cfg->origins[0];
  if (ok && strcmp(v, "*")) {
    ok = host && host > v && host[3] && !strchr(host + 3, '/');
    for (const char *p = v; ok && p < host; p++)
      ok = (*p >= 'a' && *p <= 'z') || (*p >= '0' && *p <= '9') || *p == '+' ||
           *p == '-' || *p == '.';
    for (const char *p = ok ? host + 3 : ""; ok && *p; p++)
      ok = *p > ' ' && *p < 0x7f && *p != ',' && *p != '"';
  }
  if (!ok) {
    fprintf(stderr, "stickslipd: --cors-origin needs an origin as browsers "
                    "send it (http://host:port, no path) or *\n");
    return -1;
  }
  snprintf(cfg->origins[cfg->n_origins++], sizeof cfg->origins[0], "%s", v);
  return 0;
}

/* A text option @a name into @a out (n bytes): 0, or -1 when it does not
 * fit or is missing. */
static int set_text(char *out, size_t n, const char *name, const char *v) {
  if (!v || !*v || strlen(v) >= n) {
    fprintf(stderr, "stickslipd: %s needs a value of at most %zu bytes\n", name,
            n - 1);
    return -1;
  }
  snprintf(out, n, "%s", v);
  return 0;
}

/* The default store, sqlite:<state-dir>/jobs.sqlite; the state directory
 * is --state-dir, else the first of systemd's $STATE_DIRECTORY (which the
 * unit's StateDirectory= sets), else ./stickslip-state. */
static int default_store(srv_config *cfg) {
  const char *sd = getenv("STATE_DIRECTORY");
  if (cfg->job_store[0] || cfg->no_jobs)
    return 0;
  if (!cfg->state_dir[0] && sd && *sd)
    snprintf(cfg->state_dir, sizeof cfg->state_dir, "%.*s",
             (int)strcspn(sd, ":"), sd);
  if (!cfg->state_dir[0])
    snprintf(cfg->state_dir, sizeof cfg->state_dir, "./stickslip-state");
  if (snprintf(cfg->job_store, sizeof cfg->job_store, "sqlite:%s/jobs.sqlite",
               cfg->state_dir) >= (int)sizeof cfg->job_store) {
    fprintf(stderr, "stickslipd: --state-dir is too long\n");
    return -1;
  }
  return 0;
}

/* A bad value from the variable @a name: said after the option's own
 * message, which names the option. */
static int bad_variable(const char *name) {
  fprintf(stderr, "stickslipd: (from %s)\n", name);
  return -1;
}

/* A list of @a env's comma-separated items, each given to @a add; -1 when
 * the list is longer than @a n - 1 bytes or an item is refused. */
static int each_of(srv_config *cfg, const char *name, const char *env,
                   char *list, size_t n,
                   int (*add)(srv_config *, const char *)) {
  if (strlen(env) >= n) {
    fprintf(stderr, "stickslipd: %s is over %zu bytes\n", name, n - 1);
    return -1;
  }
  snprintf(list, n, "%s", env);
  for (char *save = NULL, *a = strtok_r(list, ",", &save); a;
       a = strtok_r(NULL, ",", &save))
    if (add(cfg, a))
      return bad_variable(name);
  return 0;
}

/* Every option from the environment (STICKSLIP_...), before the flags. */
static int from_environment(srv_config *cfg) {
  char name[64];
  const char *env;
  double x;
  for (size_t k = 0; k < N_FLAGS; k++) {
    env_name(FLAGS[k].name, name, sizeof name);
    if ((env = getenv(name)) && *env) {
      if (parse(&FLAGS[k], env, &x))
        return bad_variable(name);
      set_value(cfg, &FLAGS[k], x);
    }
  }
  if ((env = getenv("STICKSLIP_BIND")) && *env) {
    if (strlen(env) >= sizeof cfg->bind) {
      fprintf(stderr, "stickslipd: STICKSLIP_BIND is too long\n");
      return -1;
    }
    snprintf(cfg->bind, sizeof cfg->bind, "%s", env);
  }
  if ((env = getenv("STICKSLIP_QUIET")) && *env)
    cfg->quiet = strcmp(env, "0") != 0;
  if ((env = getenv("STICKSLIP_NO_JOBS")) && *env)
    cfg->no_jobs = strcmp(env, "0") != 0;
  if ((env = getenv("STICKSLIP_JOB_STORE")) && *env &&
      set_text(cfg->job_store, sizeof cfg->job_store, "--job-store", env))
    return bad_variable("STICKSLIP_JOB_STORE");
  if ((env = getenv("STICKSLIP_STATE_DIR")) && *env &&
      set_text(cfg->state_dir, sizeof cfg->state_dir, "--state-dir", env))
    return bad_variable("STICKSLIP_STATE_DIR");
  if ((env = getenv("STICKSLIP_LOG_FORMAT")) && *env &&
      set_log_format(cfg, env))
    return bad_variable("STICKSLIP_LOG_FORMAT");
  char proxies[1024], origins[2048];
  if ((env = getenv("STICKSLIP_TRUSTED_PROXY")) && *env &&
      each_of(cfg, "STICKSLIP_TRUSTED_PROXY", env, proxies, sizeof proxies,
              add_proxy))
    return -1;
  if ((env = getenv("STICKSLIP_CORS_ORIGIN")) && *env &&
      each_of(cfg, "STICKSLIP_CORS_ORIGIN", env, origins, sizeof origins,
              add_origin))
    return -1;
  return 0;
}

/* --health-check: GET /health of the daemon this configuration names (its
 * port; its address, or the loopback when it listens on every address),
 * within 3 s.  The exit status: 0 when it answers 200, 1 otherwise.  For a
 * container's HEALTHCHECK, which then needs no HTTP client of its own. */
static int health_check(const srv_config *cfg) {
  char host[64], port[16];
  const char *b = cfg->bind;
  snprintf(host, sizeof host, "%s",
           !strcmp(b, "0.0.0.0") ? "127.0.0.1"
           : !strcmp(b, "::")    ? "::1"
                                 : b);
  snprintf(port, sizeof port, "%d", cfg->port);
  struct addrinfo hints, *ai = NULL;
  memset(&hints, 0, sizeof hints);
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_NUMERICHOST | AI_NUMERICSERV;
  if (getaddrinfo(host, port, &hints, &ai) != 0 || !ai) {
    fprintf(stderr, "stickslipd: --health-check: bad address %s\n", host);
    return 1;
  }
  int fd = socket(ai->ai_family, SOCK_STREAM, 0), ok = 0;
  struct timeval tv = {3, 0};
  if (fd >= 0) {
    setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  }
  if (fd >= 0 && connect(fd, ai->ai_addr, ai->ai_addrlen) == 0) {
    const char req[] = "GET /health HTTP/1.0\r\nHost: localhost\r\n\r\n";
    char buf[64] = {0};
    if (write(fd, req, sizeof req - 1) == (ssize_t)(sizeof req - 1) &&
        read(fd, buf, sizeof buf - 1) >= 12)
      ok = !strncmp(buf, "HTTP/1.", 7) && !strncmp(buf + 9, "200", 3);
  }
  if (fd >= 0)
    close(fd);
  freeaddrinfo(ai);
  if (!ok)
    fprintf(stderr, "stickslipd: --health-check: no 200 from %s:%s\n", host,
            port);
  return ok ? 0 : 1;
}

/* The environment, then the flags.  Returns -1 to exit 0 (--help,
 * --version), 2 on a bad flag, 0 to run. */
static int check_health; /* --health-check: probe a daemon, do not run one */

static int configure(srv_config *cfg, int argc, char **argv) {
  double x;
  if (from_environment(cfg))
    return 2;
  for (int i = 1; i < argc; i++) {
    const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
    const flag *f = NULL;
    for (size_t k = 0; k < N_FLAGS && !f; k++)
      if (!strcmp(a, FLAGS[k].name))
        f = &FLAGS[k];
    if (f) {
      if (parse(f, v, &x))
        return 2;
      set_value(cfg, f, x);
      i++;
    } else if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
      srv_config d;
      defaults(&d);
      usage(stdout, &d);
      return -1;
    } else if (!strcmp(a, "--version")) {
      printf("stickslipd %s\n", SS_VERSION);
      return -1;
    } else if (!strcmp(a, "--quiet")) {
      cfg->quiet = 1;
    } else if (!strcmp(a, "--health-check")) {
      check_health = 1;
    } else if (!strcmp(a, "--no-jobs")) {
      cfg->no_jobs = 1;
    } else if (!strcmp(a, "--job-store") || !strcmp(a, "--state-dir")) {
      int store = !strcmp(a, "--job-store");
      if (set_text(store ? cfg->job_store : cfg->state_dir,
                   store ? sizeof cfg->job_store : sizeof cfg->state_dir, a, v))
        return 2;
      i++;
    } else if (!strcmp(a, "--bind") && v && strlen(v) < sizeof cfg->bind) {
      snprintf(cfg->bind, sizeof cfg->bind, "%s", v);
      i++;
    } else if (!strcmp(a, "--bind")) {
      fprintf(stderr, "stickslipd: --bind needs an address\n");
      return 2;
    } else if (!strcmp(a, "--trusted-proxy")) {
      if (add_proxy(cfg, v))
        return 2;
      i++;
    } else if (!strcmp(a, "--cors-origin")) {
      if (add_origin(cfg, v))
        return 2;
      i++;
    } else if (!strcmp(a, "--log-format")) {
      if (set_log_format(cfg, v))
        return 2;
      i++;
    } else {
      fprintf(stderr, "stickslipd: unknown option %s (see --help)\n", a);
      return 2;
    }
  }
  return default_store(cfg) ? 2 : 0;
}

/* Tell the service manager @a state (a unit of Type=notify waits for
 * READY=1); a failure is said, once per state, and the daemon goes on. */
static void tell_manager(const char *state) {
  if (srv_notify(state))
    fprintf(stderr, "stickslipd: cannot notify NOTIFY_SOCKET %s: %s\n",
            getenv("NOTIFY_SOCKET"), strerror(errno));
}

int main(int argc, char **argv) {
  srv_config cfg;
  defaults(&cfg);
  int rc = configure(&cfg, argc, argv);
  if (rc)
    return rc < 0 ? 0 : rc;
  if (check_health)
    return health_check(&cfg);
  if (cfg.client_workers == 0) /* another client always finds a worker */
    cfg.client_workers = cfg.workers > 1 ? cfg.workers - 1 : 1;
  if (cfg.lim.map_threads == 0)
    cfg.lim.map_threads = cfg.workers;
  if (cfg.batch_parallel == 0)
    cfg.batch_parallel = cfg.workers;
  /* Before any thread exists: GSL must not abort, jansson's hash seed is
   * set once, and every thread inherits a mask that blocks the signals the
   * main thread waits for. */
  ss_gsl_quiet();
  json_object_seed(0);
  /* Four malloc arenas, not glibc's 8 a core: an answer is made on a
   * worker and freed on the I/O thread, and each arena keeps its own
   * high-water mark of them (1000 clients that did not read their /batch
   * answers peaked at 170 MB of RSS with the default arenas; bench/rss.py).
   * One arena peaked lowest (135 MB then, 199-210 MB in a later run against
   * 212-228 MB with four), but every thread then took its one lock for any
   * block over the thread cache, the answers' text and GSL's solvers
   * included: a /batch item of /orbit from a guess cost 68-72 us of daemon
   * CPU with one arena, 44-48 us with four, and /health waited on the lock
   * behind the workers.  malloc_trim gives every arena's free pages back
   * (monitor.c). */
  mallopt(M_ARENA_MAX, 4);
  signal(SIGPIPE, SIG_IGN);
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &set, NULL);
  struct srv_daemon *d = srv_start(&cfg);
  if (!d)
    return errno == EADDRINUSE ? 3 : 1;
  char state[192];
  snprintf(state, sizeof state, "READY=1\nSTATUS=serving on %s", srv_url(d));
  tell_manager(state);
  int sig = 0;
  /* SIGHUP (a terminal closing, a log rotation) does not stop the daemon:
   * its log is its standard error, which it never reopens */
  while (sigwait(&set, &sig) == 0 && sig == SIGHUP)
    fprintf(stderr, "stickslipd: SIGHUP ignored\n");
  fprintf(stderr, "stickslipd: signal %d, draining\n", sig);
  snprintf(state, sizeof state,
           "STOPPING=1\nSTATUS=draining on signal %d: the requests in "
           "flight finish within --drain %g s",
           sig, cfg.drain);
  tell_manager(state);
  srv_stop(d);
  fprintf(stderr, "stickslipd: stopped\n");
  return 0;
}
