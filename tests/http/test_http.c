/*
 * test_http.c: stickslipd through real HTTP: every endpoint, every
 * documented error, every limit, admission control, concurrency with a
 * short request, and a graceful SIGTERM.  Usage: test_http PATH/stickslipd
 */
#define _GNU_SOURCE
#include <arpa/inet.h>
#include <jansson.h>
#include <zlib.h>
#include <stdint.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "client.h"
#include "test.h"

static const char *BIN;
static int PORT;

#define PAPER                                                                  \
  "\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1}"
#define JSON "application/json"
/* the stick -> slip point of the paper's orbit: events every few units */
#define X0 "[1.2739277342427062,4.3629277342427093,-0.80748713672430694,1.0]"

static json_t *post(const char *path, const char *body, int want) {
  http_resp r;
  json_t *j = NULL;
  if (http_do(PORT, "POST", path, JSON, body, &r) != 0) {
    TEST_FAIL_("POST %s: no response", path);
    return NULL;
  }
  if (r.status != want)
    TEST_FAIL_("POST %s %.80s: status %d, want %d: %.300s", path, body,
               r.status, want, r.body);
  test_checks_++;
  j = json_loads(r.body, 0, NULL);
  if (!j)
    TEST_FAIL_("POST %s: body is not JSON: %.200s", path, r.body);
  http_free(&r);
  return j;
}

static double num(json_t *j, const char *path) {
  /* a tiny JSON pointer: /a/0/b */
  char buf[256], *save, *tok;
  snprintf(buf, sizeof buf, "%s", path);
  for (tok = strtok_r(buf, "/", &save); tok && j;
       tok = strtok_r(NULL, "/", &save))
    j = json_is_array(j) ? json_array_get(j, (size_t)atoi(tok))
                         : json_object_get(j, tok);
  return j && json_is_number(j) ? json_number_value(j) : NAN;
}

static void health_ok(const char *after) {
  http_resp r;
  int rc = http_do(PORT, "GET", "/health", NULL, NULL, &r);
  if (rc != 0 || r.status != 200 || !strstr(r.body, "\"ok\""))
    TEST_FAIL_("/health after %s: rc %d status %d: %.200s", after, rc, r.status,
               rc == 0 ? r.body : "");
  test_checks_++;
  http_free(&r);
}

/* EVIDENCE: README "Errors": bad input gets an application/problem+json
 * body with type, title, status, detail and, where a field is at fault, its
 * pointer.  The problem body of @a r, or NULL after a failure. */
static json_t *problem_body(const char *name, const http_resp *r, int want,
                            const char *type, const char *pointer) {
  test_checks_++;
  if (r->status != want ||
      strncmp(r->ctype, "application/problem+json", 24) != 0) {
    TEST_FAIL_("%s: status %d (%s), want %d problem+json: %.300s", name,
               r->status, r->ctype, want, r->body);
    return NULL;
  }
  json_t *j = json_loads(r->body, 0, NULL);
  const char *t = json_string_value(json_object_get(j, "type"));
  const char *p = json_string_value(json_object_get(j, "pointer"));
  if (!j || (int)num(j, "/status") != want ||
      !json_is_string(json_object_get(j, "title")) ||
      !json_is_string(json_object_get(j, "detail"))) {
    TEST_FAIL_("%s: not a problem body: %.300s", name, r->body);
    json_decref(j);
    return NULL;
  }
  if (!t || strcmp(t, type) != 0)
    TEST_FAIL_("%s: type %s, want %s", name, t ? t : "(none)", type);
  if (pointer && (!p || strcmp(p, pointer) != 0))
    TEST_FAIL_("%s: pointer %s, want %s (%.200s)", name, p ? p : "(none)",
               pointer, r->body);
  return j;
}

/* A raw request that must end in a problem and the server closing the
 * connection; @a mhd_page: answered by libmicrohttpd itself, before the
 * application, with its own HTML page (README "Errors").  The daemon
 * answers /health afterwards. */
static void expect_problem_raw(const char *name, const char *raw, size_t len,
                               int want, const char *type, int mhd_page) {
  http_resp r;
  int fd = http_send(PORT, raw, len);
  int rc = fd < 0 ? -1 : http_read(fd, 10000, &r);
  test_checks_++;
  if (rc != 0) {
    TEST_FAIL_("%s: no HTTP response (rc %d)", name, rc);
    if (fd >= 0)
      http_free(&r);
    health_ok(name);
    return;
  }
  if (!r.eof)
    TEST_FAIL_("%s: the server kept the connection open", name);
  if (mhd_page) {
    test_checks_++;
    if (r.status != want)
      TEST_FAIL_("%s: status %d, want %d: %.200s", name, r.status, want,
                 r.body);
  } else
    json_decref(problem_body(name, &r, want, type, NULL));
  http_free(&r);
  health_ok(name);
}

/* A request that must get a problem of @a type (and @a pointer, unless
 * NULL); a 405 must name the path's one method in Allow (the GET routes
 * refuse POST, the POST routes GET).  The problem body (the caller frees
 * it) or NULL. */
static json_t *expect_problem(const char *name, const char *method,
                              const char *path, const char *ctype,
                              const char *body, int want, const char *type,
                              const char *pointer) {
  http_resp r;
  int rc = http_do(PORT, method, path, ctype, body, &r);
  json_t *j = NULL;
  if (rc != 0) {
    TEST_FAIL_("%s: no response", name);
    test_checks_++;
  } else {
    j = problem_body(name, &r, want, type, pointer);
    if (want == 405) {
      const char *allow = strcmp(method, "GET") == 0 ? "POST" : "GET";
      test_checks_++;
      if (strcmp(r.allow, allow) != 0)
        TEST_FAIL_("%s: Allow \"%s\", want %s", name, r.allow, allow);
    }
  }
  http_free(&r);
  health_ok(name);
  return j;
}

static void test_endpoints(void) {
  http_resp r;
  ASSERT_EQ_INT(http_do(PORT, "GET", "/health", NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(strstr(r.body, "\"ok\"") != NULL);
  http_free(&r);
  ASSERT_EQ_INT(http_do(PORT, "GET", "/version", NULL, NULL, &r), 0);
  ASSERT_TRUE(strstr(r.body, "\"version\":\"" SS_TEST_VERSION "\"") != NULL);
  http_free(&r);
  ASSERT_EQ_INT(http_do(PORT, "GET", "/openapi.json", NULL, NULL, &r), 0);
  json_t *spec = json_loads(r.body, 0, NULL);
  ASSERT_TRUE(spec && json_object_get(spec, "openapi"));
  json_decref(spec);
  http_free(&r);

  /* /orbit, no guess: the paper's orbit */
  json_t *o = post("/orbit", "{" PAPER ",\"kind\":\"overshoot\"}", 200);
  ASSERT_NEAR(num(o, "/orbits/0/phases/0/duration"), 4.4975, 1e-3);
  ASSERT_NEAR(num(o, "/orbits/0/stability/spectral_radius"), 0.19545, 1e-4);
  ASSERT_TRUE(num(o, "/orbits/0/stability/jacobian_difference") < 1e-6);
  /* reason explains only an absence; the closest rejection is in numbers */
  ASSERT_TRUE(json_object_get(o, "reason") == NULL);
  ASSERT_TRUE(num(o, "/rejected/violation/value") <= 0);
  json_t *none = post("/orbit",
                      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,"
                      "\"ur\":0.4,\"V\":1},\"kind\":\"overshoot\"}",
                      200);
  ASSERT_EQ_INT(json_array_size(json_object_get(none, "orbits")), 0);
  ASSERT_TRUE(json_is_string(json_object_get(none, "reason")));
  ASSERT_NEAR(num(none, "/rejected/violation/value"), -0.110313724088, 1e-9);
  json_decref(none);
  /* /stability on the orbit as /orbit returned it */
  json_t *body = json_object();
  json_object_set_new(
      body, "params",
      json_deep_copy(json_object_get(json_object_get(o, "input"), "params")));
  json_object_set(body, "orbit",
                  json_array_get(json_object_get(o, "orbits"), 0));
  char *sb = json_dumps(body, JSON_COMPACT);
  json_t *s = post("/stability", sb, 200);
  ASSERT_NEAR(num(s, "/spectral_radius"),
              num(o, "/orbits/0/stability/spectral_radius"), 1e-12);
  ASSERT_TRUE(json_is_true(json_object_get(s, "feasible")));
  free(sb);
  /* /simulate from the orbit: one period returns to x0 */
  json_object_del(body, "orbit");
  json_object_set(body, "orbit",
                  json_array_get(json_object_get(o, "orbits"), 0));
  json_object_set_new(body, "t_end", json_real(num(o, "/orbits/0/period")));
  json_object_set_new(body, "events", json_false());
  sb = json_dumps(body, JSON_COMPACT);
  json_t *sim = post("/simulate", sb, 200);
  for (int i = 0; i < 3; i++) {
    char p1[32], p2[32];
    snprintf(p1, sizeof p1, "/final/x/%d", i);
    snprintf(p2, sizeof p2, "/orbits/0/x0/%d", i);
    ASSERT_NEAR(num(sim, p1), num(o, p2), 1e-12);
  }
  /* EVIDENCE: README "POST /simulate": a final-state request gets no events or
   * samples */
  ASSERT_TRUE(!json_object_get(sim, "events") &&
              !json_object_get(sim, "samples"));
  /* the third event, the return to the start, falls on t_end up to
   * rounding */
  ASSERT_TRUE(num(sim, "/n_events") >= 2 && num(sim, "/n_events") <= 3);
  free(sb);
  json_decref(sim);
  json_decref(s);
  json_decref(body);
  json_decref(o);

  /* with a guess */
  o = post("/orbit",
           "{" PAPER ",\"guess\":{\"durations\":[4.5,2.717,3.0536]},"
           "\"samples\":50}",
           200);
  ASSERT_NEAR(num(o, "/orbits/0/period"), 10.2714298553536, 1e-9);
  ASSERT_TRUE(
      json_array_size(json_object_get(
          json_object_get(json_array_get(json_object_get(o, "orbits"), 0),
                          "samples"),
          "t")) == 50);
  json_decref(o);
  /* physical units: omega = 2, so durations halve */
  o = post("/orbit",
           "{\"physical\":{\"m1\":2.5,\"m2\":0.625,\"k1\":8,\"k2\":2,"
           "\"Fs\":0.724,\"Fr\":6.178,\"v0\":2},\"kind\":\"overshoot\"}",
           200);
  ASSERT_NEAR(num(o, "/orbits/0/phases/0/duration"), 4.4974972908 / 2, 1e-8);
  ASSERT_NEAR(num(o, "/input/omega"), 2, 1e-15);
  json_decref(o);
  /* an empty answer with its reason */
  o = post("/orbit",
           "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.4,"
           "\"V\":1},\"kind\":\"overshoot\"}",
           200);
  ASSERT_EQ_INT(json_array_size(json_object_get(o, "orbits")), 0);
  ASSERT_TRUE(strstr(json_string_value(json_object_get(o, "reason")), "(3.2)"));
  json_decref(o);
  /* samples and events */
  sim = post("/simulate",
             "{" PAPER ",\"initial\":" X0 ",\"t_end\":20,"
             "\"samples\":{\"n\":11,\"from\":0,\"to\":20}}",
             200);
  ASSERT_EQ_INT(
      json_array_size(json_object_get(json_object_get(sim, "samples"), "x1")),
      11);
  ASSERT_TRUE(json_array_size(json_object_get(sim, "events")) > 0);
  json_decref(sim);
  /* metrics count what happened */
  ASSERT_EQ_INT(http_do(PORT, "GET", "/metrics", NULL, NULL, &r), 0);
  ASSERT_TRUE(strstr(r.body, "stickslip_requests_total{endpoint=\"orbit\","
                             "code=\"200\"} ") != NULL);
  ASSERT_TRUE(strstr(r.body, "stickslip_requests_in_flight") != NULL);
  ASSERT_TRUE(strstr(r.body, "stickslip_request_duration_seconds_bucket") !=
              NULL);
  http_free(&r);
}

static void test_bad_input(void) {
  char big[512];
  const char *P = "/orbit", *S = "/simulate";
  struct {
    const char *name, *path, *body;
    int want;
    const char *type, *pointer;
  } cases[] = {
      /* the JSON body's errors live in tests/api/cases, checked without
       * HTTP; these few, one or more per endpoint, prove that they leave as
       * problem+json over HTTP */
      {"malformed", P, "{", 400, "/problems/invalid-json", NULL},
      {"unknown field", P, "{" PAPER ",\"colour\":1}", 422,
       "/problems/unknown-field", "/colour"},
      {"chi out of range", P,
       "{\"params\":{\"chi\":1.5,\"eta\":4,\"us\":0.07,\"ur\":0.6,\"V\":1}}",
       422, "/problems/invalid-value", "/params/chi"},
      {"missing t_end", S, "{" PAPER ",\"initial\":" X0 "}", 422,
       "/problems/missing-field", "/t_end"},
      {"stability without z0", "/stability",
       "{" PAPER ",\"phases\":[{\"mode\":\"slip\",\"duration\":1},{\"mode\":"
       "\"stick\",\"duration\":1}]}",
       422, "/problems/missing-field", "/z0"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
    json_decref(expect_problem(cases[i].name, "POST", cases[i].path, JSON,
                               cases[i].body, cases[i].want, cases[i].type,
                               cases[i].pointer));
  json_decref(expect_problem("wrong method", "GET", "/orbit", NULL, NULL, 405,
                             "/problems/method-not-allowed", NULL));
  json_decref(expect_problem("wrong method on GET route", "POST", "/health",
                             JSON, "{}", 405, "/problems/method-not-allowed",
                             NULL));
  json_decref(expect_problem("unknown path", "GET", "/nope", NULL, NULL, 404,
                             "/problems/not-found", NULL));
  json_decref(expect_problem("double slash", "GET", "//orbit", NULL, NULL, 404,
                             "/problems/not-found", NULL));
  json_decref(expect_problem("wrong content type", "POST", "/orbit",
                             "text/plain", "{" PAPER "}", 415,
                             "/problems/unsupported-media-type", NULL));
  json_decref(expect_problem("no content type", "POST", "/orbit", NULL,
                             "{" PAPER "}", 415,
                             "/problems/unsupported-media-type", NULL));
  /* 100000-deep nesting: refused by the codec's depth scan before jansson
   * recurses (jansson's own refusal would not name the depth), and the
   * daemon lives on; the depth limit itself is the codec cases
   * orbit-depth-32-accepted and orbit-depth-33-refused */
  {
    size_t n = 100000;
    char *b = malloc(n + 1);
    memset(b, '[', n);
    b[n] = 0;
    json_t *j = expect_problem("deep nesting", "POST", "/orbit", JSON, b, 400,
                               "/problems/invalid-json", NULL);
    const char *detail = json_string_value(json_object_get(j, "detail"));
    ASSERT_TRUE(detail && strstr(detail, "deeper than 32 levels"));
    json_decref(j);
    free(b);
  }
  /* a 20 MB body: refused from Content-Length */
  {
    size_t n = 20u << 20;
    char *req = malloc(n + 512);
    int h = snprintf(req, 512,
                     "POST /orbit HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
                     "Content-Type: application/json\r\nContent-Length: %zu"
                     "\r\n\r\n",
                     n);
    memset(req + h, ' ', n);
    expect_problem_raw("20 MB body", req, (size_t)h + n, 413,
                       "/problems/limit-exceeded", 0);
    /* chunked, no Content-Length: refused when it passes the limit */
    h = snprintf(req, 512,
                 "POST /orbit HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
                 "Content-Type: application/json\r\nTransfer-Encoding: chunked"
                 "\r\n\r\n");
    size_t off = (size_t)h;
    for (int c = 0; c < 40; c++) {
      off += (size_t)sprintf(req + off, "10000\r\n");
      memset(req + off, ' ', 0x10000);
      off += 0x10000;
      off += (size_t)sprintf(req + off, "\r\n");
    }
    off += (size_t)sprintf(req + off, "0\r\n\r\n");
    expect_problem_raw("chunked 2.5 MB body", req, off, 413,
                       "/problems/limit-exceeded", 0);
    free(req);
  }
  snprintf(big, sizeof big,
           "POST /orbit HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
           "Content-Type: application/json\r\nContent-Length: "
           "99999999999999999999999\r\n\r\n{}");
  expect_problem_raw("overflowing Content-Length", big, strlen(big), 413, NULL,
                     1);
}

/* Has the server closed this connection?  Waits up to ms. */
static int closed_by_server(int fd, int ms) {
  struct pollfd p = {fd, POLLIN, 0};
  char c;
  if (poll(&p, 1, ms) <= 0)
    return 0;
  return recv(fd, &c, 1, 0) == 0;
}

/* Computations for the pool tests: LONG needs minutes (it ends only by
 * cancellation or shutdown), MEDIUM about a second, CHEAP microseconds. */
static const char *LONG_SIM =
    "{" PAPER ",\"initial\":" X0 ",\"t_end\":9e8,\"events\":false}";
static const char *MEDIUM_SIM =
    "{" PAPER ",\"initial\":" X0 ",\"t_end\":1.5e7,\"events\":false}";
static const char *CHEAP =
    "{" PAPER ",\"phases\":[{\"mode\":\"slip\",\"duration\":4.497497290813434},"
    "{\"mode\":\"overshoot\",\"duration\":2.7226655903272814},{\"mode\":"
    "\"stick\",\"duration\":3.05126697421287}],\"z0\":[1.1834277342427062,"
    "3.910427734242709,-0.8074871367243069,1.0]}";

static double mono(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Send a POST and return the socket to read the answer from. */
static int start(int port, const char *path, const char *body) {
  size_t len;
  char *req = http_request("POST", path, JSON, body, &len);
  int fd = http_send(port, req, len);
  free(req);
  return fd;
}

/* A counter of the daemon's /metrics, or -1. */
static double metric(int port, const char *name) {
  http_resp r;
  double v = -1;
  if (http_do(port, "GET", "/metrics", NULL, NULL, &r) == 0) {
    char line[96];
    snprintf(line, sizeof line, "\n%s ", name);
    const char *at = strstr(r.body, line);
    if (at)
      v = atof(at + strlen(line));
  }
  http_free(&r);
  return v;
}

/* CPU seconds the process has used (utime + stime from /proc). */
static double cpu_seconds(pid_t pid) {
  char path[64], buf[1024];
  snprintf(path, sizeof path, "/proc/%d/stat", (int)pid);
  FILE *f = fopen(path, "r");
  if (!f)
    return -1;
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  buf[n] = 0;
  char *p = strrchr(buf, ')');
  unsigned long ut = 0, st = 0;
  /* after the command: state ppid pgrp session tty tpgid flags minflt
   * cminflt majflt cmajflt utime stime */
  if (!p || sscanf(p + 2, "%*c %*d %*d %*d %*d %*d %*u %*u %*u %*u %*u %lu %lu",
                   &ut, &st) != 2)
    return -1;
  return (double)(ut + st) / (double)sysconf(_SC_CLK_TCK);
}

/* The latency of a cheap computation from @a src, and its status. */
typedef struct probe {
  int port, status;
  const char *src;
  double seconds;
} probe;

static void *cheap_probe(void *vp) {
  probe *p = vp;
  http_resp r;
  http_set_source(p->src);
  double t0 = mono();
  p->status = http_do(p->port, "POST", "/stability", JSON, CHEAP, &r) == 0
                  ? r.status
                  : -1;
  p->seconds = mono() - t0;
  http_free(&r);
  return NULL;
}

/* EVIDENCE: README "Limits" (Architecture): per-client queues served round
 * robin, a full queue answered 503 at once, another client's cheap work not
 * kept waiting by a client's long work, and a client that hangs up stops its
 * work */
static void test_pool(void) {
  daemon_proc d;
  const char *args[] = {"--workers",
                        "2",
                        "--client-workers",
                        "1",
                        "--client-queue",
                        "2",
                        "--max-events",
                        "1000000000",
                        "--max-horizon",
                        "1e10",
                        "--max-seconds",
                        "600",
                        "--drain",
                        "60",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  /* client A (127.0.0.1): one long computation runs, two wait, three are
   * refused at once */
  int fd[6];
  for (int i = 0; i < 6; i++) {
    fd[i] = start(d.port, "/simulate", LONG_SIM);
    usleep(20000);
  }
  usleep(200000);
  int refused = 0, pending = 0;
  for (int i = 0; i < 6; i++) {
    struct pollfd p = {fd[i], POLLIN, 0};
    if (poll(&p, 1, 0) > 0) {
      http_resp r;
      ASSERT_EQ_INT(http_read(fd[i], 2000, &r), 0);
      ASSERT_EQ_INT(r.status, 503);
      ASSERT_TRUE(strcmp(r.retry_after, "1") == 0);
      http_free(&r);
      fd[i] = -1;
      refused++;
    } else {
      pending++;
    }
  }
  printf("pool: 6 long requests from one client: %d waiting or running, %d "
         "refused at once\n",
         pending, refused);
  ASSERT_EQ_INT(refused, 3);
  /* a /health meanwhile, from A itself */
  http_resp r;
  double t0 = mono();
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  double dt = mono() - t0;
  ASSERT_EQ_INT(r.status, 200);
  json_t *h = json_loads(r.body, 0, NULL);
  long inflight = (long)num(h, "/in_flight");
  json_decref(h);
  http_free(&r);
  printf("pool: /health in %.2f ms with %ld requests in flight\n", dt * 1e3,
         inflight);
  ASSERT_TRUE(inflight >= 3);
  /* client B (127.0.0.2): cheap computations are not kept waiting */
  double worst = 0;
  for (int i = 0; i < 20; i++) {
    probe pb = {d.port, 0, "127.0.0.2", 0};
    cheap_probe(&pb);
    ASSERT_EQ_INT(pb.status, 200);
    worst = fmax(worst, pb.seconds);
  }
  printf("pool: 20 cheap /stability from another client while the first "
         "keeps its long work in flight: slowest %.2f ms\n",
         worst * 1e3);
  ASSERT_TRUE(worst < 1.0);
  /* A hangs up: its waiting work is dropped, its running work stops */
  t0 = mono();
  for (int i = 0; i < 6; i++)
    if (fd[i] >= 0)
      close(fd[i]);
  double cancelled = 0;
  while (mono() - t0 < 5 &&
         (cancelled = metric(d.port, "stickslip_cancelled_total")) < 3)
    usleep(10000);
  double t_stop = mono() - t0;
  usleep(300000);
  double cpu1 = cpu_seconds(d.pid);
  usleep(500000);
  double cpu2 = cpu_seconds(d.pid);
  printf("pool: after the hang-up, 3 computations cancelled in %.0f ms; "
         "then %.3f CPU-s in 0.5 s\n",
         t_stop * 1e3, cpu2 - cpu1);
  ASSERT_TRUE(cancelled == 3);
  ASSERT_TRUE(cpu2 - cpu1 < 0.1);
  /* A's slot is free again at once */
  probe pa = {d.port, 0, "127.0.0.1", 0};
  cheap_probe(&pa);
  ASSERT_EQ_INT(pa.status, 200);
  ASSERT_TRUE(pa.seconds < 1.0);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  char *log = daemon_log(&d);
  ASSERT_TRUE(log && strstr(log, "\"method\":\"GET\",\"path\":\"/health\","
                                 "\"status\":200,"));
  free(log);
  unlink(d.log_path);
}

/* EVIDENCE: README "Limits" (Signals): SIGTERM refuses new connections,
 * finishes the work in flight, answers what waits with 503 and exits 0;
 * SIGHUP does not stop the daemon */
static void test_shutdown(void) {
  daemon_proc d;
  const char *args[] = {"--workers",
                        "1",
                        "--client-queue",
                        "4",
                        "--max-events",
                        "100000000",
                        "--max-horizon",
                        "1e8",
                        "--max-seconds",
                        "600",
                        "--drain",
                        "60",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  kill(d.pid, SIGHUP);
  usleep(100000);
  http_resp r;
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  int running = start(d.port, "/simulate", MEDIUM_SIM);
  usleep(50000);
  int waiting = start(d.port, "/simulate", MEDIUM_SIM);
  usleep(100000);
  kill(d.pid, SIGTERM);
  usleep(100000);
  int late = http_connect(d.port);
  ASSERT_TRUE(late < 0); /* refused: the listening socket is closed */
  if (late >= 0)
    close(late);
  http_resp a, b;
  ASSERT_EQ_INT(http_read(running, 60000, &a), 0);
  ASSERT_EQ_INT(http_read(waiting, 60000, &b), 0);
  printf("shutdown: running request %d, waiting request %d\n", a.status,
         b.status);
  ASSERT_EQ_INT(a.status, 200);
  ASSERT_EQ_INT(b.status, 503);
  ASSERT_TRUE(strstr(b.body, "shutting-down") != NULL);
  http_free(&a);
  http_free(&b);
  int st = 0;
  waitpid(d.pid, &st, 0);
  ASSERT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0);
  char *log = daemon_log(&d);
  ASSERT_TRUE(log && strstr(log, "SIGHUP ignored"));
  free(log);
  unlink(d.log_path);
}

/* EVIDENCE: README "Limits" (Architecture): two Content-Length headers,
 * Content-Length with Transfer-Encoding, or two Host headers are refused
 * with 400 and the connection is closed (none of these requests asks for
 * Connection: close).  A GET with a body is answered (stated nowhere). */
static void test_framing(void) {
  static const char *bad[] = {
      "POST /orbit HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
      "Content-Length: 2\r\nContent-Length: 60\r\n\r\n{}",
      "POST /orbit HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
      "Content-Length: 7\r\nTransfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0"
      "\r\n\r\n",
      "GET /health HTTP/1.1\r\nHost: x\r\nHost: y\r\n\r\n",
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    expect_problem_raw("smuggling framing", bad[i], strlen(bad[i]), 400,
                       "/problems/bad-request", 0);
  const char *get_body =
      "GET /health HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
      "Content-Length: 5\r\n\r\nhello";
  http_resp r;
  ASSERT_EQ_INT(http_raw(PORT, get_body, strlen(get_body), &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  /* the header block: 24 KiB are read, 40 KiB refused (README: 32 KiB) */
  for (int big = 0; big < 2; big++) {
    size_t n = big ? 40000 : 24000;
    char *req = malloc(n + 128);
    int k = snprintf(req, 128,
                     "GET /health HTTP/1.1\r\nHost: x\r\nConnection: "
                     "close\r\nX-Big: ");
    memset(req + k, 'a', n);
    memcpy(req + k + n, "\r\n\r\n", 5);
    ASSERT_EQ_INT(http_raw(PORT, req, (size_t)k + n + 4, &r), 0);
    ASSERT_EQ_INT(r.status, big ? 431 : 200);
    http_free(&r);
    free(req);
  }
}

/* EVIDENCE: README "Limits" (Architecture): a connection that does not
 * deliver its request within --request-timeout is closed, while others are
 * served */
static void test_slow_client(void) {
  daemon_proc d;
  const char *args[] = {"--request-timeout", "1", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  int slow[20];
  for (int i = 0; i < 20; i++) {
    slow[i] = http_connect(d.port);
    ASSERT_TRUE(slow[i] >= 0 && send(slow[i], "GET /hea", 8, 0) == 8);
  }
  double t0 = mono();
  http_resp r;
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  double dt = mono() - t0;
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  for (int i = 0; i < 20; i++) {
    /* a byte now and then does not keep it open past the deadline */
    ASSERT_TRUE(send(slow[i], "l", 1, MSG_NOSIGNAL) == 1);
  }
  ASSERT_TRUE(!closed_by_server(slow[0], 500));
  int closed = 0;
  for (int i = 0; i < 20; i++) {
    closed += closed_by_server(slow[i], 3000);
    close(slow[i]);
  }
  double total = mono() - t0;
  printf("slow clients: /health in %.2f ms beside 20 slow connections, all "
         "%d closed after %.2f s (deadline 1 s)\n",
         dt * 1e3, closed, total);
  ASSERT_EQ_INT(closed, 20);
  ASSERT_TRUE(metric(d.port, "stickslip_slow_closed_total") >= 20);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* A long /simulate sent with X-Forwarded-For: @a xff; its socket. */
static int start_forwarded(int port, const char *xff) {
  char req[1024];
  int n = snprintf(req, sizeof req,
                   "POST /simulate HTTP/1.1\r\nHost: x\r\nContent-Type: "
                   "application/json\r\nX-Forwarded-For: %s\r\n"
                   "Content-Length: %zu\r\n\r\n%s",
                   xff, strlen(LONG_SIM), LONG_SIM);
  return http_send(port, req, (size_t)n);
}

/* The status of the answer on @a fd within @a ms, or 0 (none yet). */
static int status_within(int fd, int ms) {
  char head[16] = {0};
  struct pollfd p = {fd, POLLIN, 0};
  if (poll(&p, 1, ms) > 0 && recv(fd, head, 12, 0) == 12)
    return atoi(head + 9);
  return 0;
}

/* Which client a request is, with and without --trusted-proxy: with one
 * computation per client and no waiting, a second long request of the same
 * client gets 503 at once, another client's runs.  Behind a trusted proxy
 * the client is the first address of X-Forwarded-For; from any other peer
 * the header is ignored. */
static void run_forwarded(int trusted, const char *xff1, const char *xff2,
                          int want2) {
  daemon_proc d;
  const char *args[] = {"--client-workers",
                        "1",
                        "--client-queue",
                        "0",
                        "--workers",
                        "2",
                        "--max-events",
                        "1000000000",
                        "--max-horizon",
                        "1e10",
                        "--max-seconds",
                        "600",
                        "--trusted-proxy",
                        trusted ? "127.0.0.1" : "127.0.0.9",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  int a = start_forwarded(d.port, xff1);
  usleep(200000);
  int b = start_forwarded(d.port, xff2);
  int sb = status_within(b, 500);
  if (sb != want2)
    printf("forwarded: trusted %d, second from %s: %d, want %d\n", trusted,
           xff2, sb, want2);
  ASSERT_EQ_INT(sb, want2);
  close(a);
  close(b);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* EVIDENCE: README "Limits": --trusted-proxy */
static void test_forwarded(void) {
  const char *first = "10.0.0.1, 127.0.0.1";
  run_forwarded(1, first, "10.0.0.2", 0);    /* another client: it runs */
  run_forwarded(1, first, " 10.0.0.1", 503); /* the same client */
  /* an untrusted peer: the header is ignored, both are 127.0.0.1 */
  run_forwarded(0, first, "10.0.0.2", 503);
  /* not an address: the client is the peer */
  run_forwarded(1, "unknown", "::1x", 503);
  printf("forwarded: clients told apart by X-Forwarded-For from a trusted "
         "proxy only\n");
}

/* VmHWM (peak resident set) of a process, MiB; -1 when unknown. */
static double peak_rss_mib(pid_t pid) {
  char path[64], line[256];
  double v = -1;
  snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
  FILE *f = fopen(path, "r");
  while (f && fgets(line, sizeof line, f))
    if (strncmp(line, "VmHWM:", 6) == 0)
      v = atof(line + 6) / 1024;
  if (f)
    fclose(f);
  return v;
}

/* 100000 samples and some 2900 events: a 10.7 MB answer whose arrays hold
 * about 4.3 MB in the daemon. */
static const char *BIG_SIM = "{" PAPER ",\"initial\":" X0 ",\"t_end\":10000,"
                             "\"samples\":{\"n\":100000}}";

/* EVIDENCE: README "Limits": --memory-budget; large answers are streamed
 * (chunked) from the result, and what answers in flight hold is bounded:
 * clients that never read get 503 once the budget is spent */
static void test_memory(void) {
  daemon_proc d;
  const char *args[] = {"--memory-budget",  "16", "--workers", "2",
                        "--client-workers", "2",  NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  /* a reader gets the whole answer, chunked */
  http_resp r;
  ASSERT_EQ_INT(http_do(d.port, "POST", "/simulate", JSON, BIG_SIM, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(r.chunked);
  json_t *j = json_loads(r.body, 0, NULL);
  ASSERT_TRUE(j != NULL);
  ASSERT_EQ_INT(
      json_array_size(json_object_get(json_object_get(j, "samples"), "mode")),
      100000);
  ASSERT_TRUE(json_array_size(json_object_get(j, "events")) > 1000);
  ASSERT_NEAR(num(j, "/final/t"), 10000, 0);
  json_decref(j);
  http_free(&r);
  /* 16 clients that never read: each answer holds ~4.3 MB, so after
   * three or four of them the budget of 16 MiB is spent */
  enum { N = 16 };
  int fd[N], ok = 0, busy = 0;
  for (int i = 0; i < N; i++) {
    fd[i] = start(d.port, "/simulate", BIG_SIM);
    ASSERT_TRUE(fd[i] >= 0);
    setsockopt(fd[i], SOL_SOCKET, SO_RCVBUF, &(int){4096}, sizeof(int));
  }
  /* every one gets the head of its answer: 200 and the start of the
   * stream, or 503 */
  for (int i = 0; i < N; i++) {
    char head[16] = {0};
    struct pollfd p = {fd[i], POLLIN, 0};
    if (poll(&p, 1, 30000) > 0 && recv(fd[i], head, 12, 0) == 12) {
      ok += strncmp(head + 9, "200", 3) == 0;
      busy += strncmp(head + 9, "503", 3) == 0;
    }
  }
  double held = metric(d.port, "stickslip_memory_held_bytes") / 1048576;
  double peak = metric(d.port, "stickslip_memory_held_peak_bytes") / 1048576;
  double rss = peak_rss_mib(d.pid);
  printf("memory: 16 non-reading clients, budget 16 MiB: %d answers "
         "(held %.1f MiB, peak %.1f), %d refused 503; peak RSS %.1f MiB\n",
         ok, held, peak, busy, rss);
  ASSERT_EQ_INT(ok + busy, N);
  ASSERT_TRUE(busy >= N / 2);
  ASSERT_TRUE(ok >= 2);
  /* what may be admitted past the budget: the answers being computed when
   * it was spent, at most one per worker */
  ASSERT_TRUE(peak <= 16 + 2 * 4.5);
  ASSERT_TRUE(held >= 16 && held <= peak);
  ASSERT_TRUE(metric(d.port, "stickslip_rejected_memory_total") >= busy);
  for (int i = 0; i < N; i++)
    close(fd[i]);
  /* hang-ups give the bytes back */
  double t0 = mono();
  while (metric(d.port, "stickslip_memory_held_bytes") > 0 && mono() - t0 < 5)
    usleep(20000);
  ASSERT_NEAR(metric(d.port, "stickslip_memory_held_bytes"), 0, 0);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* Structural equality with a relative tolerance on numbers. */
static int same_json(json_t *a, json_t *b, double rtol, char *where, size_t n) {
  if (json_is_number(a) && json_is_number(b)) {
    double x = json_number_value(a), y = json_number_value(b);
    if (fabs(x - y) <= rtol * fmax(1.0, fmax(fabs(x), fabs(y))))
      return 1;
    snprintf(where, n, "%.17g != %.17g", x, y);
    return 0;
  }
  if (json_typeof(a) != json_typeof(b)) {
    snprintf(where, n, "types differ");
    return 0;
  }
  if (json_is_object(a)) {
    const char *k;
    json_t *v;
    if (json_object_size(a) != json_object_size(b)) {
      snprintf(where, n, "object sizes differ");
      return 0;
    }
    json_object_foreach(a, k, v) {
      json_t *w = json_object_get(b, k);
      if (!w) {
        snprintf(where, n, "/%s missing", k);
        return 0;
      }
      if (!same_json(v, w, rtol, where, n)) {
        size_t l = strlen(where);
        char tmp[256];
        snprintf(tmp, sizeof tmp, "/%s%s", k, where);
        snprintf(where, n, "%s", tmp);
        (void)l;
        return 0;
      }
    }
    return 1;
  }
  if (json_is_array(a)) {
    if (json_array_size(a) != json_array_size(b)) {
      snprintf(where, n, "array sizes differ");
      return 0;
    }
    for (size_t i = 0; i < json_array_size(a); i++)
      if (!same_json(json_array_get(a, i), json_array_get(b, i), rtol, where,
                     n))
        return 0;
    return 1;
  }
  if (json_equal(a, b))
    return 1;
  snprintf(where, n, "values differ");
  return 0;
}

/* EVIDENCE: README "POST /map": a complete cell holds what /orbit finds
 * for its parameters, the others at least what /orbit finds there too on
 * this sweep (continued from their neighbours); the last line counts the
 * cells, and fields selects the orbits' fields. */
static void test_map_against_orbit(void) {
  const char *P = "{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":%.17g,\"V\":1}";
  const char *body =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
      "\"axes\":[{\"parameter\":\"ur\",\"from\":0.6,\"to\":0.9,\"n\":7}],"
      "\"kind\":\"overshoot\",\"search_every\":3,"
      "\"fields\":[\"period\",\"modes\",\"found_by\"]}";
  http_resp r;
  ASSERT_EQ_INT(http_do(PORT, "POST", "/map", JSON, body, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(strstr(r.ctype, "application/x-ndjson") != NULL);
  int lines = 0, complete = 0, compared = 0;
  for (const char *t = r.body, *e; t && *t; t = e + 1) {
    if (!(e = strchr(t, '\n')))
      break;
    json_t *l = json_loadb(t, (size_t)(e - t), 0, NULL);
    ASSERT_TRUE(l != NULL);
    if (!l)
      break;
    if (json_is_true(json_object_get(l, "done"))) {
      ASSERT_EQ_INT(json_integer_value(json_object_get(l, "cells")), 7);
      ASSERT_EQ_INT(json_integer_value(json_object_get(l, "complete")),
                    complete);
      json_decref(l);
      lines++;
      continue;
    }
    lines++;
    double ur =
        json_number_value(json_object_get(json_object_get(l, "at"), "ur"));
    json_t *orbits = json_object_get(l, "orbits");
    int is_complete = json_is_true(json_object_get(l, "complete"));
    complete += is_complete;
    /* only the fields asked for */
    json_t *o0 = json_array_get(orbits, 0);
    if (o0) {
      ASSERT_EQ_INT((int)json_object_size(o0), 3);
      ASSERT_TRUE(json_is_string(json_object_get(o0, "found_by")));
    }
    char req[512], params[160];
    snprintf(params, sizeof params, P, ur);
    snprintf(req, sizeof req,
             "{\"params\":%s,\"kind\":\"overshoot\",\"finite_difference\":"
             "false}",
             params);
    http_resp ro;
    ASSERT_EQ_INT(http_do(PORT, "POST", "/orbit", JSON, req, &ro), 0);
    ASSERT_EQ_INT(ro.status, 200);
    json_t *oj = json_loads(ro.body, 0, NULL);
    json_t *alone = json_object_get(oj, "orbits");
    /* every orbit /orbit finds is in the cell; a complete cell has no
     * fewer */
    for (size_t k = 0; k < json_array_size(alone); k++) {
      double per = json_number_value(
          json_object_get(json_array_get(alone, k), "period"));
      int found = 0;
      for (size_t i = 0; i < json_array_size(orbits) && !found; i++)
        found = fabs(json_number_value(
                         json_object_get(json_array_get(orbits, i), "period")) -
                     per) < 1e-9 * per;
      if (!found)
        TEST_FAIL_("/map at ur %.17g lacks the orbit of period %.17g that "
                   "/orbit finds",
                   ur, per);
      test_checks_++;
    }
    if (is_complete)
      ASSERT_EQ_INT((int)json_array_size(orbits), (int)json_array_size(alone));
    compared += (int)json_array_size(alone);
    json_decref(oj);
    http_free(&ro);
    json_decref(l);
  }
  ASSERT_EQ_INT(lines, 8);
  ASSERT_TRUE(complete >= 3 && compared >= 5);
  http_free(&r);
}

/* The lines of NDJSON text @a t as an array ordered by "index" (a batch's
 * items; a map's cells, whose index is an array, in their order), the line
 * without one last, "seconds" dropped; NULL when a line is not JSON. */
static json_t *ndjson_sorted(const char *t) {
  json_t *a = json_array(), *last = NULL;
  for (const char *e; t && *t; t = e + 1) {
    if (!(e = strchr(t, '\n')))
      e = t + strlen(t);
    json_t *l = json_loadb(t, (size_t)(e - t), 0, NULL);
    if (!l) {
      json_decref(a);
      json_decref(last);
      return NULL;
    }
    json_object_del(l, "seconds");
    json_t *ix = json_object_get(l, "index");
    if (json_is_array(ix)) { /* a map's cells, in the order written */
      json_array_append_new(a, l);
    } else if (!json_is_integer(ix)) {
      json_decref(last);
      last = l;
    } else {
      size_t i = (size_t)json_integer_value(ix);
      while (json_array_size(a) <= i)
        json_array_append_new(a, json_null());
      json_array_set_new(a, i, l);
    }
    if (!*e)
      break;
  }
  if (last)
    json_array_append_new(a, last);
  return a;
}

/* EVIDENCE: README "HTTP API": the contract is api/openapi.yaml, served at
 * GET /openapi.json.  That its examples are what the daemon answers is not
 * stated in README; this test replays them. */
static void test_spec_examples(void) {
  http_resp r;
  ASSERT_EQ_INT(http_do(PORT, "GET", "/openapi.json", NULL, NULL, &r), 0);
  json_t *spec = json_loads(r.body, 0, NULL);
  http_free(&r);
  ASSERT_TRUE(spec != NULL);
  const char *path;
  json_t *item;
  int replayed = 0;
  json_object_foreach(json_object_get(spec, "paths"), path, item) {
    json_t *post = json_object_get(item, "post");
    if (!post)
      continue;
    json_t *reqex = json_object_get(
        json_object_get(
            json_object_get(json_object_get(post, "requestBody"), "content"),
            "application/json"),
        "examples");
    const char *name;
    json_t *ex;
    json_object_foreach(reqex, name, ex) {
      /* find the response example of the same name */
      const char *code;
      json_t *resp, *want = NULL;
      int want_status = 0;
      json_object_foreach(json_object_get(post, "responses"), code, resp) {
        const char *ct;
        json_t *media;
        json_object_foreach(json_object_get(resp, "content"), ct, media) {
          json_t *e = json_object_get(json_object_get(media, "examples"), name);
          if (e) {
            want = json_object_get(e, "value");
            want_status = atoi(code);
          }
        }
      }
      ASSERT_TRUE(want != NULL);
      if (!want)
        continue;
      char *body = json_dumps(json_object_get(ex, "value"), JSON_COMPACT);
      http_resp rr;
      ASSERT_EQ_INT(http_do(PORT, "POST", path, JSON, body, &rr), 0);
      ASSERT_EQ_INT(rr.status, want_status);
      /* an NDJSON example is its text: the same lines, in any order, all
       * but the time taken */
      json_t *got = json_is_string(want) ? ndjson_sorted(rr.body)
                                         : json_loads(rr.body, 0, NULL);
      /* a problem names its request, which differs every time */
      if (json_is_object(got))
        json_object_del(got, "request_id");
      json_t *want_j =
          json_is_string(want) ? ndjson_sorted(json_string_value(want)) : NULL;
      if (want_j)
        want = want_j;
      char where[256] = "";
      if (!got || !same_json(want, got, 1e-7, where, sizeof where))
        TEST_FAIL_("spec example %s %s differs from the answer at %s", path,
                   name, where);
      test_checks_++;
      replayed++;
      json_decref(got);
      json_decref(want_j);
      http_free(&rr);
      free(body);
    }
  }
  printf("spec: %d examples replayed\n", replayed);
  ASSERT_TRUE(replayed >= 8);
  json_decref(spec);
}

/* EVIDENCE: README "Limits" (the table): per-IP connection limit and idle
 * timeout */
static void test_connection_limits(void) {
  daemon_proc d;
  const char *args[] = {"--per-ip-connections", "2", "--connection-timeout",
                        "1", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  int a = http_connect(d.port), b = http_connect(d.port);
  ASSERT_TRUE(a >= 0 && b >= 0);
  usleep(100000);
  /* a third connection from the same address is dropped at once */
  http_resp r;
  ASSERT_TRUE(http_do(d.port, "GET", "/health", NULL, NULL, &r) != 0);
  http_free(&r);
  /* idle connections are closed after the timeout */
  ASSERT_TRUE(closed_by_server(a, 4000));
  ASSERT_TRUE(closed_by_server(b, 4000));
  close(a);
  close(b);
  usleep(100000);
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  /* EVIDENCE: README "Limits" (Signals): SIGINT stops the daemon as SIGTERM
   * does */
  ASSERT_EQ_INT(daemon_stop_with(&d, SIGINT), 0);
  unlink(d.log_path);
}

/* EVIDENCE: README "Limits": each per-request limit has its flag;
 * README "Errors": a limit that stops a request is a 422 limit-exceeded whose
 * limit and limit_value name it, a body over --max-body a 413, nesting
 * deeper than the limit a 400 invalid-json.  That a search over --max-orbits
 * answers 200 with the first orbits and counts the rest in
 * search.truncated is stated nowhere in README. */
static void test_flag_limits(void) {
  daemon_proc d;
  const char *args[] = {"--max-events",
                        "50",
                        "--max-orbits",
                        "1",
                        "--max-depth",
                        "4",
                        "--max-body",
                        "1000",
                        "--max-samples",
                        "10",
                        "--max-horizon",
                        "1e9",
                        "--max-points",
                        "10",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;
  struct {
    const char *name, *path, *body, *limit;
    double limit_value;
    const char *pointer;
  } cases[] = {
      {"max-events", "/simulate",
       "{" PAPER ",\"initial\":" X0 ",\"t_end\":1000,\"events\":false}",
       "max_events", 50, "/t_end"},
      {"max-samples", "/simulate",
       "{" PAPER ",\"initial\":" X0 ",\"t_end\":10,\"samples\":{\"n\":11}}",
       "max_samples", 10, "/samples/n"},
      {"max-points", "/continue",
       "{" PAPER ",\"guess\":{\"durations\":[4.4975,2.7227,3.0513]},"
       "\"parameter\":\"ur\",\"range\":[0.3,1.5],\"max_points\":11}",
       "max_points", 10, "/max_points"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    json_t *j = expect_problem(cases[i].name, "POST", cases[i].path, JSON,
                               cases[i].body, 422, "/problems/limit-exceeded",
                               cases[i].pointer);
    const char *l = json_string_value(json_object_get(j, "limit"));
    ASSERT_TRUE(l && strcmp(l, cases[i].limit) == 0);
    ASSERT_NEAR(num(j, "/limit_value"), cases[i].limit_value, 0);
    json_decref(j);
  }
  /* stop_after under --max-events: the run stops at its 40th event, inside
   * the limit, over a horizon that would need some 2.6e8 */
  {
    json_t *j = post("/simulate",
                     "{" PAPER ",\"initial\":" X0 ",\"t_end\":9e8,"
                     "\"events\":false,\"stop_after\":40}",
                     200);
    ASSERT_EQ_INT((int)num(j, "/n_events"), 40);
    json_decref(j);
  }
  /* max-depth 4: five levels are refused (under the default of 32 this body
   * would reach the decoder and get 422 unknown-field /a) */
  {
    json_t *j =
        expect_problem("max-depth", "POST", "/orbit", JSON, "{\"a\":[[[[1]]]]}",
                       400, "/problems/invalid-json", NULL);
    const char *detail = json_string_value(json_object_get(j, "detail"));
    ASSERT_TRUE(detail && strstr(detail, "deeper than 4 levels"));
    json_decref(j);
  }
  /* max-orbits 1: the search over all kinds finds 4 orbits for the paper's
   * data without the limit (the overshoot orbit, two stick-slip orbits and
   * a period-3 orbit; about 10 ms); one is returned and the 3 others are
   * counted in search.truncated (with their repeats, 8 here) */
  {
    json_t *j =
        post("/orbit",
             "{" PAPER ",\"kind\":\"all\",\"finite_difference\":false}", 200);
    ASSERT_EQ_INT(json_array_size(json_object_get(j, "orbits")), 1);
    ASSERT_TRUE(num(j, "/search/truncated") >= 3);
    json_decref(j);
  }
  /* max-body: 413 from Content-Length */
  {
    char body[2001];
    memset(body, ' ', 2000);
    body[0] = '{';
    body[1999] = '}';
    body[2000] = 0;
    json_t *j = expect_problem("max-body flag", "POST", "/orbit", JSON, body,
                               413, "/problems/limit-exceeded", NULL);
    const char *l = json_string_value(json_object_get(j, "limit"));
    ASSERT_TRUE(l && strcmp(l, "max_body") == 0);
    ASSERT_NEAR(num(j, "/limit_value"), 1000, 0);
    json_decref(j);
  }
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* EVIDENCE: README "Limits": --max-seconds bounds the compute time of a
 * request, and /simulate stops when it runs out; README "Errors": a 422
 * limit-exceeded that names max_seconds */
static void test_time_limit(void) {
  daemon_proc d;
  const char *args[] = {
      "--max-seconds", "0.05", "--max-events", "1000000000", "--max-horizon",
      "1e9",           NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;
  /* about 2.6e8 events: 172 s without the limit on a 2-core test machine
   * (release build), some 3000 times the budget, so over 0.05 s on any
   * machine.  The answer names the flag's value and comes when that budget
   * runs out: the default budget (10 s) would also end this run with a
   * max_seconds 422, but later */
  double t0 = mono();
  json_t *j = post("/simulate",
                   "{" PAPER ",\"initial\":" X0 ",\"t_end\":9e8,"
                   "\"events\":false}",
                   422);
  double dt = mono() - t0;
  const char *l = json_string_value(json_object_get(j, "limit"));
  ASSERT_TRUE(l && strcmp(l, "max_seconds") == 0);
  ASSERT_NEAR(num(j, "/limit_value"), 0.05, 1e-12);
  printf("max-seconds 0.05: answered 422 after %.3f s\n", dt);
  ASSERT_TRUE(dt < 2);
  json_decref(j);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* ---- POST /batch ---------------------------------------------------------
 */

#define MAX_LINES 64

/* The lines of a streamed NDJSON answer as they arrive, with the time each
 * one was complete. */
typedef struct ndjson {
  int status;
  char ctype[64];
  json_t *line[MAX_LINES];
  double at[MAX_LINES];
  int n;
  int complete; /* the last chunk (0-length) came */
} ndjson;

/* Decode what has come of a chunked answer: the body so far into @a body
 * (room for the raw length); whether the last chunk has come. */
static int dechunk_partial(const char *raw, char *body, size_t *blen) {
  const char *in = strstr(raw, "\r\n\r\n");
  *blen = 0;
  if (!in)
    return 0;
  in += 4;
  for (;;) {
    char *end;
    unsigned long n = strtoul(in, &end, 16);
    if (end == in || !strstr(end, "\r\n"))
      return 0;
    const char *data = strstr(end, "\r\n") + 2;
    if (n == 0)
      return 1;
    if (strlen(data) < n + 2)
      return 0;
    memcpy(body + *blen, data, n);
    *blen += n;
    in = data + n + 2;
  }
}

/* Read the answer on @a fd until it is complete, @a want lines have come
 * (0: all), or @a timeout_ms pass without a byte.  Does not close @a fd. */
static void read_ndjson(int fd, int timeout_ms, int want, ndjson *out) {
  static char raw[1 << 20], body[1 << 20];
  size_t rlen = 0;
  memset(out, 0, sizeof *out);
  while (rlen + 1 < sizeof raw) {
    struct pollfd p = {fd, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0)
      break;
    ssize_t k = recv(fd, raw + rlen, sizeof raw - 1 - rlen, 0);
    if (k <= 0)
      break;
    rlen += (size_t)k;
    raw[rlen] = 0;
    if (!out->status) {
      sscanf(raw, "HTTP/1.1 %d", &out->status);
      const char *ct = strcasestr(raw, "\r\nContent-Type: ");
      if (ct)
        sscanf(ct + 16, "%63[^\r]", out->ctype);
    }
    size_t blen;
    out->complete = dechunk_partial(raw, body, &blen);
    /* every whole line not seen yet */
    int seen = 0;
    for (size_t a = 0, b = 0; b < blen; b++) {
      if (body[b] != '\n')
        continue;
      if (seen++ >= out->n && out->n < MAX_LINES) {
        out->line[out->n] = json_loadb(body + a, b - a, 0, NULL);
        if (!out->line[out->n])
          TEST_FAIL_("batch line %d is not JSON: %.*s", out->n,
                     (int)(b - a > 200 ? 200 : b - a), body + a);
        out->at[out->n++] = mono();
      }
      a = b + 1;
    }
    if (out->complete || (want && out->n >= want))
      break;
  }
}

static void ndjson_free(ndjson *nd) {
  for (int i = 0; i < nd->n; i++)
    json_decref(nd->line[i]);
  nd->n = 0;
}

/* The line of item @a index, or NULL. */
static json_t *item_line(const ndjson *nd, int index) {
  for (int i = 0; i < nd->n; i++) {
    json_t *ix = json_object_get(nd->line[i], "index");
    if (ix && json_integer_value(ix) == index)
      return nd->line[i];
  }
  return NULL;
}

static const char *str_at(json_t *j, const char *k1, const char *k2) {
  json_t *v = json_object_get(j, k1);
  if (k2)
    v = json_object_get(v, k2);
  return json_is_string(v) ? json_string_value(v) : "";
}

/* EVIDENCE: README "Batches": an NDJSON line per item as it is done, a bad
 * item answered by its own line while the others go on, a last line with
 * the counts, the batch refused as a whole only when it is not a list of
 * items, items in flight bounded, a hang-up cancelling the rest, and a
 * shutdown answering the items not started with 503 */
static void test_batch(void) {
  daemon_proc d;
  const char *args[] = {"--workers",
                        "2",
                        "--client-workers",
                        "1",
                        "--batch-parallel",
                        "2",
                        "--max-batch-items",
                        "8",
                        "--max-events",
                        "1000000000",
                        "--max-horizon",
                        "1e10",
                        "--max-seconds",
                        "600",
                        "--drain",
                        "60",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;

  /* good and bad items */
  static const char *mixed =
      "{\"requests\":["
      "{\"id\":\"cheap\",\"path\":\"/stability\",\"body\":%s},"
      "{\"id\":7,\"path\":\"/nope\",\"body\":{}},"
      "{\"id\":\"chi\",\"path\":\"/orbit\",\"body\":{\"params\":{\"chi\":-1,"
      "\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1}}},"
      "{\"id\":\"meta\",\"path\":\"/health\",\"body\":{}},"
      "[1,2],"
      "{\"id\":\"nobody\",\"path\":\"/simulate\"},"
      "{\"id\":{\"a\":1},\"path\":\"/orbit\",\"body\":{}},"
      "{\"id\":\"orbit\",\"path\":\"/orbit\",\"body\":{" PAPER "}}]}";
  char body[4096];
  snprintf(body, sizeof body, mixed, CHEAP);
  int fd = start(d.port, "/batch", body);
  ndjson nd;
  read_ndjson(fd, 30000, 0, &nd);
  close(fd);
  ASSERT_EQ_INT(nd.status, 200);
  ASSERT_TRUE(strcmp(nd.ctype, "application/x-ndjson") == 0);
  ASSERT_TRUE(nd.complete);
  ASSERT_EQ_INT(nd.n, 9);
  static const struct {
    const char *id;
    int status;
    const char *type, *pointer;
  } want[8] = {{"cheap", 200, NULL, NULL},
               {NULL, 404, "/problems/not-found", "/path"},
               {"chi", 422, "/problems/invalid-value", "/body/params/chi"},
               {"meta", 422, "/problems/invalid-value", "/path"},
               {NULL, 422, "/problems/invalid-type", ""},
               {"nobody", 422, "/problems/missing-field", "/body"},
               {NULL, 422, "/problems/invalid-type", "/id"},
               {"orbit", 200, NULL, NULL}};
  for (int i = 0; i < 8; i++) {
    json_t *l = item_line(&nd, i);
    ASSERT_TRUE(l != NULL);
    if (!l)
      continue;
    ASSERT_EQ_INT((int)json_integer_value(json_object_get(l, "status")),
                  want[i].status);
    if (want[i].id)
      ASSERT_TRUE(strcmp(str_at(l, "id", NULL), want[i].id) == 0);
    if (want[i].type) {
      ASSERT_TRUE(strcmp(str_at(l, "body", "type"), want[i].type) == 0);
      ASSERT_TRUE(strcmp(str_at(l, "body", "pointer"), want[i].pointer) == 0);
    }
  }
  json_t *l1 = item_line(&nd, 1);
  ASSERT_TRUE(l1 && json_integer_value(json_object_get(l1, "id")) == 7);
  json_t *l4 = item_line(&nd, 4);
  ASSERT_TRUE(l4 && json_is_null(json_object_get(l4, "id")));
  json_t *last = nd.line[nd.n - 1];
  ASSERT_TRUE(json_is_true(json_object_get(last, "done")));
  ASSERT_EQ_INT((int)json_integer_value(json_object_get(last, "ok")), 2);
  ASSERT_EQ_INT((int)json_integer_value(json_object_get(last, "failed")), 6);
  ASSERT_TRUE(json_is_number(json_object_get(last, "seconds")));
  /* an item's answer is the answer to the same request sent alone */
  json_t *alone = post("/stability", CHEAP, 200);
  char where[256] = "";
  json_t *in_batch = json_object_get(item_line(&nd, 0), "body");
  if (!same_json(alone, in_batch, 0, where, sizeof where))
    TEST_FAIL_("a batch item differs from the request alone at %s", where);
  json_decref(alone);
  ndjson_free(&nd);

  /* the batch refused as a whole */
  static const struct {
    const char *body, *type, *pointer;
  } whole[] = {
      {"[]", "/problems/invalid-type", NULL},
      {"{}", "/problems/missing-field", "/requests"},
      {"{\"requests\":{}}", "/problems/invalid-type", "/requests"},
      {"{\"requests\":[]}", "/problems/invalid-value", "/requests"},
      {"{\"requests\":[],\"x\":1}", "/problems/unknown-field", "/x"},
      {"{\"requests\":[1,2,3,4,5,6,7,8,9]}", "/problems/limit-exceeded",
       "/requests"},
      {"{\"requests\":[1,2", "/problems/invalid-json", NULL},
  };
  for (size_t i = 0; i < sizeof whole / sizeof whole[0]; i++) {
    http_resp r;
    ASSERT_EQ_INT(http_do(d.port, "POST", "/batch", JSON, whole[i].body, &r),
                  0);
    json_t *p = json_loads(r.body, 0, NULL);
    if (r.status < 400 || r.status >= 500 ||
        strcmp(r.ctype, "application/problem+json") != 0 ||
        strcmp(str_at(p, "type", NULL), whole[i].type) != 0 ||
        (whole[i].pointer &&
         strcmp(str_at(p, "pointer", NULL), whole[i].pointer) != 0))
      TEST_FAIL_("batch %s: %d %s", whole[i].body, r.status, r.body);
    test_checks_++;
    if (i == 5)
      ASSERT_TRUE(strcmp(str_at(p, "limit", NULL), "max_batch_items") == 0);
    json_decref(p);
    http_free(&r);
  }

  /* the first line comes as soon as its item is done, before the last
   * item is computed */
  snprintf(body, sizeof body,
           "{\"requests\":[{\"id\":1,\"path\":\"/simulate\",\"body\":%s},"
           "{\"id\":2,\"path\":\"/simulate\",\"body\":%s},"
           "{\"id\":0,\"path\":\"/stability\",\"body\":%s}]}",
           MEDIUM_SIM, MEDIUM_SIM, CHEAP);
  double t0 = mono();
  fd = start(d.port, "/batch", body);
  read_ndjson(fd, 60000, 0, &nd);
  close(fd);
  ASSERT_EQ_INT(nd.n, 4);
  if (nd.n == 4) {
    printf("batch: lines at %.3f %.3f %.3f s, the last line at %.3f s\n",
           nd.at[0] - t0, nd.at[1] - t0, nd.at[2] - t0, nd.at[3] - t0);
    /* one item of the client runs at a time (--client-workers 1): the
     * first simulation's line came while the second one still ran */
    ASSERT_TRUE(nd.at[3] - nd.at[0] > 0.25 * (nd.at[0] - t0));
    ASSERT_EQ_INT((int)json_integer_value(json_object_get(nd.line[3], "ok")),
                  3);
  }
  ndjson_free(&nd);

  /* a hang-up stops the batch: what runs stops, nothing more starts */
  double cancelled0 = metric(d.port, "stickslip_cancelled_total");
  char big[8192];
  size_t k = (size_t)snprintf(big, sizeof big, "{\"requests\":[");
  for (int i = 0; i < 8; i++)
    k += (size_t)snprintf(big + k, sizeof big - k,
                          "%s{\"id\":%d,\"path\":\"/simulate\",\"body\":%s}",
                          i ? "," : "", i, LONG_SIM);
  snprintf(big + k, sizeof big - k, "]}");
  fd = start(d.port, "/batch", big);
  usleep(300000);
  /* meanwhile another client's cheap work is not kept waiting */
  double worst = 0;
  for (int i = 0; i < 10; i++) {
    probe pb = {d.port, 0, "127.0.0.2", 0};
    cheap_probe(&pb);
    ASSERT_EQ_INT(pb.status, 200);
    worst = fmax(worst, pb.seconds);
  }
  printf("batch: 10 cheap /stability from another client during a batch of "
         "long items: slowest %.2f ms\n",
         worst * 1e3);
  ASSERT_TRUE(worst < 1.0);
  t0 = mono();
  close(fd);
  double cancelled = cancelled0;
  while (mono() - t0 < 5 &&
         (cancelled = metric(d.port, "stickslip_cancelled_total")) <
             cancelled0 + 2)
    usleep(10000);
  double t_stop = mono() - t0;
  usleep(300000);
  double cpu1 = cpu_seconds(d.pid);
  usleep(500000);
  double cpu2 = cpu_seconds(d.pid);
  double held = metric(d.port, "stickslip_memory_held_bytes");
  printf("batch: hang-up after 0.3 s: %.0f items in flight cancelled in %.0f "
         "ms, then %.3f CPU-s in 0.5 s, %.0f bytes held\n",
         cancelled - cancelled0, t_stop * 1e3, cpu2 - cpu1, held);
  /* the two items in flight (one running, one waiting); the other six
   * never started */
  ASSERT_TRUE(cancelled - cancelled0 == 2);
  ASSERT_TRUE(cpu2 - cpu1 < 0.1);
  ASSERT_TRUE(held == 0);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);

  /* SIGTERM mid-batch: the item that runs finishes, the others are
   * answered 503, the batch ends with its last line, the daemon exits 0 */
  const char *args1[] = {"--workers",
                         "1",
                         "--max-events",
                         "1000000000",
                         "--max-horizon",
                         "1e10",
                         "--max-seconds",
                         "600",
                         "--drain",
                         "60",
                         NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args1, &d), 0);
  snprintf(body, sizeof body,
           "{\"requests\":[{\"id\":1,\"path\":\"/simulate\",\"body\":%s},"
           "{\"id\":2,\"path\":\"/simulate\",\"body\":%s},"
           "{\"id\":3,\"path\":\"/stability\",\"body\":%s}]}",
           MEDIUM_SIM, MEDIUM_SIM, CHEAP);
  fd = start(d.port, "/batch", body);
  usleep(200000);
  kill(d.pid, SIGTERM);
  read_ndjson(fd, 60000, 0, &nd);
  close(fd);
  ASSERT_EQ_INT(nd.n, 4);
  ASSERT_TRUE(nd.complete);
  if (nd.n == 4) {
    json_t *first = item_line(&nd, 0);
    ASSERT_EQ_INT((int)json_integer_value(json_object_get(first, "status")),
                  200);
    for (int i = 1; i < 3; i++) {
      json_t *l = item_line(&nd, i);
      ASSERT_EQ_INT((int)json_integer_value(json_object_get(l, "status")), 503);
      ASSERT_TRUE(
          strcmp(str_at(l, "body", "type"), "/problems/shutting-down") == 0);
    }
    ASSERT_EQ_INT((int)json_integer_value(json_object_get(nd.line[3], "ok")),
                  1);
  }
  ndjson_free(&nd);
  int st = 0;
  waitpid(d.pid, &st, 0);
  ASSERT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0);
  unlink(d.log_path);
}

/* The value of header @a name in the raw response @a raw (into @a out), or
 * NULL. */
static const char *header_of(const char *raw, const char *name, char *out,
                             size_t n) {
  char key[80];
  snprintf(key, sizeof key, "\r\n%s: ", name);
  const char *h = raw ? strcasestr(raw, key) : NULL;
  const char *end = h ? strstr(h + 2, "\r\n") : NULL;
  if (!h || !end)
    return NULL;
  h += strlen(key);
  snprintf(out, n, "%.*s", (int)(end - h), h);
  return out;
}

/* A GET or POST with extra header lines; the answer in @a r. */
static int raw_with(int port, const char *method, const char *path,
                    const char *headers, const char *body, http_resp *r) {
  char req[4096];
  int k = snprintf(req, sizeof req,
                   "%s %s HTTP/1.1\r\nHost: t\r\nConnection: close\r\n%s"
                   "Content-Type: application/json\r\nContent-Length: %zu\r\n"
                   "\r\n%s",
                   method, path, headers, body ? strlen(body) : 0,
                   body ? body : "");
  return http_raw(port, req, (size_t)k, r);
}

static int is_hex16(const char *s) {
  if (!s || strlen(s) != 16)
    return 0;
  for (int i = 0; i < 16; i++)
    if (!strchr("0123456789abcdef", s[i]))
      return 0;
  return 1;
}

/* @a p (n bytes, gzip) inflated, NUL-terminated (malloc'd), or NULL. */
static char *gunzip(const char *p, size_t n, size_t *out_len) {
  z_stream zs;
  memset(&zs, 0, sizeof zs);
  if (inflateInit2(&zs, 15 + 16) != Z_OK)
    return NULL;
  size_t cap = 4 * n + 1024, len = 0;
  char *out = malloc(cap);
  zs.next_in = (Bytef *)(uintptr_t)p;
  zs.avail_in = (uInt)n;
  int rc = Z_OK;
  while (out && rc == Z_OK) {
    if (cap - len < 4096) {
      char *o = realloc(out, cap *= 2);
      if (!o) {
        free(out);
        out = NULL;
        break;
      }
      out = o;
    }
    zs.next_out = (Bytef *)out + len;
    zs.avail_out = (uInt)(cap - len - 1);
    rc = inflate(&zs, Z_NO_FLUSH);
    len = cap - 1 - zs.avail_out;
  }
  inflateEnd(&zs);
  if (rc != Z_STREAM_END || zs.avail_in) {
    free(out);
    return NULL;
  }
  out[len] = 0;
  *out_len = len;
  return out;
}

/* EVIDENCE: README "Operations": gzip for a client that accepts it, whole
 * answers and streamed ones alike, and none for one that refuses it or for
 * a small answer. */
static void test_gzip(void) {
  http_resp plain, gz;
  char v[128];
  size_t n = 0;
  /* a whole answer */
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json", "", NULL, &plain), 0);
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json",
                         "Accept-Encoding: gzip\r\n", NULL, &gz),
                0);
  ASSERT_TRUE(header_of(gz.raw, "Content-Encoding", v, sizeof v) &&
              !strcmp(v, "gzip"));
  ASSERT_TRUE(header_of(gz.raw, "Vary", v, sizeof v) &&
              !strcmp(v, "Accept-Encoding"));
  ASSERT_TRUE(header_of(gz.raw, "ETag", v, sizeof v) && strstr(v, "-gzip\""));
  char *text = gunzip(gz.body, gz.len, &n);
  ASSERT_TRUE(text && n == plain.len && !memcmp(text, plain.body, n));
  printf("gzip: /openapi.json %zu -> %zu bytes\n", plain.len, gz.len);
  free(text);
  /* its gzip validator gets 304 */
  char inm[200];
  snprintf(inm, sizeof inm, "Accept-Encoding: gzip\r\nIf-None-Match: %s\r\n",
           v);
  http_free(&gz);
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json", inm, NULL, &gz), 0);
  ASSERT_EQ_INT(gz.status, 304);
  http_free(&gz);
  http_free(&plain);
  /* a streamed answer (over the streaming threshold) */
  const char *sim =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
      "\"initial\":[1.2739277342427062,4.362927734242709,-0.8074871367243069,"
      "1.0],\"t_end\":100,\"samples\":{\"n\":2000,\"from\":0,\"to\":100}}";
  ASSERT_EQ_INT(raw_with(PORT, "POST", "/simulate", "", sim, &plain), 0);
  ASSERT_EQ_INT(raw_with(PORT, "POST", "/simulate",
                         "Accept-Encoding: br, gzip;q=0.5\r\n", sim, &gz),
                0);
  ASSERT_EQ_INT(gz.status, 200);
  ASSERT_TRUE(plain.chunked && gz.chunked);
  ASSERT_TRUE(header_of(gz.raw, "Content-Encoding", v, sizeof v) &&
              !strcmp(v, "gzip"));
  text = gunzip(gz.body, gz.len, &n);
  ASSERT_TRUE(text && n == plain.len && !memcmp(text, plain.body, n));
  printf("gzip: a 2000-sample /simulate %zu -> %zu bytes, streamed\n",
         plain.len, gz.len);
  free(text);
  http_free(&gz);
  http_free(&plain);
  /* a batch: its NDJSON gzipped piece by piece, each flushed */
  const char *bat =
      "{\"requests\":[{\"id\":\"s\",\"path\":\"/simulate\",\"body\":"
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"initial\":[1.27,4.36,-0.8,1],\"t_end\":50,\"samples\":"
      "{\"n\":300}}},{\"id\":\"o\",\"path\":\"/orbit\",\"body\":{\"params\":"
      "{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
      "\"guess\":{\"durations\":[4.4975,2.7227,3.0513]}}}]}";
  ASSERT_EQ_INT(
      raw_with(PORT, "POST", "/batch", "Accept-Encoding: gzip\r\n", bat, &gz),
      0);
  ASSERT_EQ_INT(gz.status, 200);
  ASSERT_TRUE(header_of(gz.raw, "Content-Encoding", v, sizeof v) &&
              !strcmp(v, "gzip"));
  text = gunzip(gz.body, gz.len, &n);
  ASSERT_TRUE(text != NULL);
  int lines = 0, ok_lines = 0;
  for (char *l = text ? strtok(text, "\n") : NULL; l; l = strtok(NULL, "\n")) {
    json_t *j = json_loads(l, 0, NULL);
    lines++;
    ok_lines += j && (json_integer_value(json_object_get(j, "status")) == 200 ||
                      json_is_true(json_object_get(j, "done")));
    json_decref(j);
  }
  ASSERT_EQ_INT(lines, 3);
  ASSERT_EQ_INT(ok_lines, 3);
  printf("gzip: a /batch of 2 items, %zu -> %zu bytes\n", n, gz.len);
  free(text);
  http_free(&gz);
  /* refused (q=0), or too small to gain */
  const char *no[][2] = {{"/openapi.json", "Accept-Encoding: gzip;q=0\r\n"},
                         {"/openapi.json", "Accept-Encoding: xgzip\r\n"},
                         {"/health", "Accept-Encoding: gzip\r\n"}};
  for (int i = 0; i < 3; i++) {
    ASSERT_EQ_INT(raw_with(PORT, "GET", no[i][0], no[i][1], NULL, &gz), 0);
    ASSERT_EQ_INT(gz.status, 200);
    ASSERT_TRUE(!header_of(gz.raw, "Content-Encoding", v, sizeof v));
    ASSERT_TRUE(gz.len == strlen(gz.body));
    http_free(&gz);
  }
}

/* EVIDENCE: README "Operations": X-Request-Id taken or made, echoed in the
 * response and in a problem's body and in the access log line, which is
 * JSON; exact status codes, build and process metrics; a validator and a
 * lifetime for /openapi.json. */
static void test_operations(const daemon_proc *d) {
  http_resp r;
  char v[128], w[128];
  /* given */
  ASSERT_EQ_INT(
      raw_with(PORT, "GET", "/health", "X-Request-Id: job-7.a:1\r\n", NULL, &r),
      0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(header_of(r.raw, "X-Request-Id", v, sizeof v) &&
              !strcmp(v, "job-7.a:1"));
  size_t health_bytes = strlen(r.body);
  http_free(&r);
  /* made: 16 hex digits, another for the next request; one that is not
   * made of the allowed characters, or too long, is replaced */
  const char *bad[] = {"", "X-Request-Id: has space\r\n",
                       "X-Request-Id: "
                       "0123456789012345678901234567890123456789012345678901234"
                       "567890123456789\r\n"};
  for (int i = 0; i < 3; i++) {
    ASSERT_EQ_INT(raw_with(PORT, "GET", "/version", bad[i], NULL, &r), 0);
    ASSERT_TRUE(header_of(r.raw, "X-Request-Id", v, sizeof v) && is_hex16(v));
    if (i)
      ASSERT_TRUE(strcmp(v, w) != 0);
    snprintf(w, sizeof w, "%s", v);
    http_free(&r);
  }
  /* a problem names its request */
  ASSERT_EQ_INT(raw_with(PORT, "POST", "/orbit", "X-Request-Id: bad-one\r\n",
                         "{\"params\":", &r),
                0);
  ASSERT_EQ_INT(r.status, 400);
  json_t *pb = json_loads(r.body, 0, NULL);
  ASSERT_TRUE(
      pb &&
      !strcmp(json_string_value(json_object_get(pb, "request_id")), "bad-one"));
  ASSERT_TRUE(json_is_string(json_object_get(pb, "type")));
  json_decref(pb);
  http_free(&r);
  /* the contract: a validator, a lifetime, and 304 when it is current */
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json", "", NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(header_of(r.raw, "ETag", v, sizeof v) && v[0] == '"');
  ASSERT_TRUE(header_of(r.raw, "Cache-Control", w, sizeof w) &&
              strstr(w, "max-age="));
  http_free(&r);
  char inm[200];
  snprintf(inm, sizeof inm, "If-None-Match: %s\r\n", v);
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json", inm, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 304);
  ASSERT_TRUE(!r.body || !*r.body);
  http_free(&r);
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json",
                         "If-None-Match: \"0000000000000000\"\r\n", NULL, &r),
                0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  /* metrics: exact codes, the build, the process */
  ASSERT_EQ_INT(http_do(PORT, "GET", "/metrics", NULL, NULL, &r), 0);
  ASSERT_TRUE(strstr(r.body, "stickslip_requests_total{endpoint=\"orbit\","
                             "code=\"400\"} ") != NULL);
  ASSERT_TRUE(strstr(r.body, "stickslip_requests_total{endpoint=\"openapi\","
                             "code=\"304\"} 1\n") != NULL);
  snprintf(w, sizeof w, "stickslip_build_info{version=\"%s\",",
           SS_TEST_VERSION);
  ASSERT_TRUE(strstr(r.body, w) != NULL);
  const char *proc[] = {"process_cpu_seconds_total ",
                        "process_resident_memory_bytes ", "process_open_fds ",
                        "process_max_fds ", "process_start_time_seconds "};
  for (int i = 0; i < 5; i++)
    if (!strstr(r.body, proc[i]))
      TEST_FAIL_("/metrics lacks %s", proc[i]);
  http_free(&r);
  /* --health-check probes a daemon: 0 when it answers, 1 when none does */
  char cmd[512];
  snprintf(cmd, sizeof cmd, "%s --health-check --port %d 2>/dev/null", BIN,
           PORT);
  int hc = system(cmd);
  ASSERT_TRUE(WIFEXITED(hc) && WEXITSTATUS(hc) == 0);
  snprintf(cmd, sizeof cmd, "%s --health-check --port 1 2>/dev/null", BIN);
  hc = system(cmd);
  ASSERT_TRUE(WIFEXITED(hc) && WEXITSTATUS(hc) == 1);
  /* the access log: a JSON line per request, with its id and bytes */
  usleep(100000);
  char *log = daemon_log(d);
  int found = 0;
  for (char *line = log ? strtok(log, "\n") : NULL; line;
       line = strtok(NULL, "\n")) {
    json_t *j = json_loads(line, 0, NULL);
    if (j && !strcmp(json_string_value(json_object_get(j, "request_id")) ?: "",
                     "job-7.a:1")) {
      found = 1;
      ASSERT_EQ_INT((int)json_integer_value(json_object_get(j, "status")), 200);
      ASSERT_EQ_INT((int)json_integer_value(json_object_get(j, "bytes")),
                    (int)health_bytes);
      ASSERT_TRUE(
          !strcmp(json_string_value(json_object_get(j, "path")), "/health"));
      ASSERT_TRUE(!strcmp(json_string_value(json_object_get(j, "client")),
                          "127.0.0.1"));
      ASSERT_TRUE(json_integer_value(json_object_get(j, "us")) >= 0);
      const char *t = json_string_value(json_object_get(j, "time"));
      ASSERT_TRUE(t && strlen(t) == 24 && t[10] == 'T' && t[23] == 'Z');
    }
    json_decref(j);
  }
  ASSERT_TRUE(found);
  free(log);
}

/* A POST /orbit of 200 bytes to a daemon started with @a args and the
 * environment STICKSLIP_MAX_BODY=100, STICKSLIP_LOG_FORMAT=plain: its
 * status; the log's last /orbit line must be plain. */
static int env_daemon_status(const char *const *args) {
  daemon_proc d;
  setenv("STICKSLIP_MAX_BODY", "100", 1);
  setenv("STICKSLIP_LOG_FORMAT", "plain", 1);
  int rc = daemon_start(BIN, args, &d);
  unsetenv("STICKSLIP_MAX_BODY");
  unsetenv("STICKSLIP_LOG_FORMAT");
  ASSERT_EQ_INT(rc, 0);
  if (rc)
    return -1;
  char body[201];
  memset(body, ' ', 200);
  body[200] = 0;
  body[0] = '{';
  body[199] = '}';
  http_resp r;
  int status = -1;
  if (http_do(d.port, "POST", "/orbit", JSON, body, &r) == 0)
    status = r.status;
  http_free(&r);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  char *log = daemon_log(&d);
  char want[32];
  snprintf(want, sizeof want, "POST /orbit %d ", status);
  ASSERT_TRUE(log && strstr(log, want));
  free(log);
  unlink(d.log_path);
  return status;
}

/* EVIDENCE: README "Operations": every option from the environment, the
 * command line winning; the plain log format. */
static void test_environment(void) {
  ASSERT_EQ_INT(env_daemon_status(NULL), 413);
  const char *args[] = {"--max-body", "1000", NULL};
  ASSERT_EQ_INT(env_daemon_status(args), 422);
  /* a bad value in the environment stops the daemon at once */
  daemon_proc d;
  setenv("STICKSLIP_WORKERS", "many", 1);
  int rc = daemon_start(BIN, NULL, &d);
  unsetenv("STICKSLIP_WORKERS");
  ASSERT_TRUE(rc != 0);
  if (rc == 0)
    daemon_stop(&d);
  unlink(d.log_path);
}

/* The samples of orbit 0 of an /orbit answer placed for a curve: one
 * period from its stick -> slip point to the next, starting in slip, the
 * modes changing at its three events only, each event sampled on both
 * sides; the columns asked for and no others. */
static void check_orbit_curve(const char *body, const char *what) {
  json_t *o = post("/orbit", body, 200);
  json_t *orb = json_array_get(json_object_get(o, "orbits"), 0);
  json_t *s = json_object_get(orb, "samples");
  json_t *t = json_object_get(s, "t"), *mode = json_object_get(s, "mode");
  size_t n = json_array_size(t);
  double period = json_number_value(json_object_get(orb, "period"));
  ASSERT_TRUE(n >= 8 && json_array_size(mode) == n);
  ASSERT_EQ_INT((int)json_object_size(s), 3); /* t, x2, mode */
  ASSERT_NEAR(json_number_value(json_array_get(t, 0)), 0, 0);
  ASSERT_NEAR(json_number_value(json_array_get(t, n - 1)), period,
              1e-9 * period);
  ASSERT_TRUE(!strcmp(json_string_value(json_array_get(mode, 0)), "slip"));
  int changes = 0;
  for (size_t i = 1; i < n; i++)
    if (strcmp(json_string_value(json_array_get(mode, i)),
               json_string_value(json_array_get(mode, i - 1)))) {
      changes++;
      /* both sides of the event at the same time */
      ASSERT_NEAR(json_number_value(json_array_get(t, i)),
                  json_number_value(json_array_get(t, i - 1)), 1e-12 * period);
    }
  ASSERT_EQ_INT(changes, 3);
  printf("curve of the paper's orbit, %s: %zu samples over %.6g\n", what, n,
         period);
  json_decref(o);
}

/* EVIDENCE: README "Samples placed for a curve": an orbit's curve spans
 * exactly its period, from slip, in the request's units (dimensionless and
 * physical alike), with only the columns asked for. */
static void test_orbit_curves(void) {
  check_orbit_curve("{" PAPER ",\"kind\":\"overshoot\",\"samples\":{"
                    "\"tolerance\":1e-3,\"fields\":[\"t\",\"x2\",\"mode\"]}}",
                    "dimensionless");
  check_orbit_curve(
      "{\"physical\":{\"m1\":2.5,\"m2\":0.625,\"k1\":8,\"k2\":2,\"Fs\":"
      "0.724,\"Fr\":6.178,\"v0\":2},\"kind\":\"overshoot\",\"samples\":{"
      "\"tolerance\":1e-3,\"scale\":{\"v1\":2,\"v2\":2},\"fields\":[\"t\","
      "\"x2\",\"mode\"]}}",
      "physical");
}

/* Whether the raw response @a raw has the header line "name: value". */
static int has_header_line(const char *raw, const char *name,
                           const char *value) {
  char line[160];
  snprintf(line, sizeof line, "\r\n%s: %s\r\n", name, value);
  const char *end = raw ? strstr(raw, "\r\n\r\n") : NULL;
  const char *h = raw ? strcasestr(raw, line) : NULL;
  return h && end && h < end;
}

/* EVIDENCE: README "The explorer": GET / is the page, its assets under
 * /explorer/, each with its media type, a validator and a lifetime (304 to
 * a client that has it); the page with a Content-Security-Policy that
 * allows only its own files. */
static void test_explorer_files(void) {
  const char *files[][2] = {
      {"/", "text/html; charset=utf-8"},
      {"/explorer/app.js", "text/javascript; charset=utf-8"},
      {"/explorer/style.css", "text/css; charset=utf-8"}};
  char v[200], inm[260];
  for (int i = 0; i < 3; i++) {
    http_resp r;
    ASSERT_EQ_INT(raw_with(PORT, "GET", files[i][0], "", NULL, &r), 0);
    ASSERT_EQ_INT(r.status, 200);
    ASSERT_TRUE(r.len > 0);
    ASSERT_TRUE(header_of(r.raw, "Content-Type", v, sizeof v) &&
                !strcmp(v, files[i][1]));
    ASSERT_TRUE(header_of(r.raw, "Cache-Control", v, sizeof v) != NULL);
    if (i == 0) {
      ASSERT_TRUE(header_of(r.raw, "Content-Security-Policy", v, sizeof v) &&
                  strstr(v, "default-src 'self'"));
      ASSERT_TRUE(strstr(r.body, "/explorer/app.js") &&
                  strstr(r.body, "/explorer/style.css"));
    }
    ASSERT_TRUE(header_of(r.raw, "ETag", v, sizeof v) != NULL);
    snprintf(inm, sizeof inm, "If-None-Match: %s\r\n", v);
    http_free(&r);
    ASSERT_EQ_INT(raw_with(PORT, "GET", files[i][0], inm, NULL, &r), 0);
    ASSERT_EQ_INT(r.status, 304);
    http_free(&r);
  }
  /* no CORS by default: an OPTIONS gets what the path takes, no more */
  http_resp r;
  ASSERT_EQ_INT(raw_with(PORT, "OPTIONS", "/orbit",
                         "Origin: http://elsewhere.example\r\n"
                         "Access-Control-Request-Method: POST\r\n",
                         NULL, &r),
                0);
  ASSERT_EQ_INT(r.status, 204);
  ASSERT_TRUE(has_header_line(r.raw, "Allow", "POST, OPTIONS"));
  ASSERT_TRUE(!header_of(r.raw, "Access-Control-Allow-Origin", v, sizeof v));
  ASSERT_TRUE(!has_header_line(r.raw, "Vary", "Origin"));
  http_free(&r);
}

/* EVIDENCE: README "The explorer" (CORS): with --cors-origin, a page of
 * that origin gets its preflight answered and may read every answer
 * (success, problem, streamed, batch) with the headers it needs; a page of
 * another origin gets no Access-Control header; Vary: Origin on all. */
static void test_cors(void) {
  daemon_proc d;
  const char *args[] = {"--cors-origin", "http://app.example:3000", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  const char *mine = "Origin: http://app.example:3000\r\n";
  const char *other = "Origin: http://other.example\r\n";
  char v[200], hdr[300];
  http_resp r;
  /* the preflight */
  snprintf(hdr, sizeof hdr,
           "%sAccess-Control-Request-Method: POST\r\n"
           "Access-Control-Request-Headers: content-type\r\n",
           mine);
  ASSERT_EQ_INT(raw_with(d.port, "OPTIONS", "/orbit", hdr, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 204);
  ASSERT_TRUE(has_header_line(r.raw, "Access-Control-Allow-Origin",
                              "http://app.example:3000"));
  ASSERT_TRUE(header_of(r.raw, "Access-Control-Allow-Methods", v, sizeof v) &&
              strstr(v, "POST"));
  ASSERT_TRUE(header_of(r.raw, "Access-Control-Allow-Headers", v, sizeof v) &&
              strcasestr(v, "content-type"));
  ASSERT_TRUE(header_of(r.raw, "Access-Control-Max-Age", v, sizeof v) != NULL);
  ASSERT_TRUE(has_header_line(r.raw, "Vary", "Origin"));
  http_free(&r);
  /* an unknown path is still 404 */
  ASSERT_EQ_INT(raw_with(d.port, "OPTIONS", "/nowhere", mine, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 404);
  http_free(&r);
  /* the actual requests: an answer, a problem, a streamed answer, a batch */
  const char *orbit =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"guess\":{\"durations\":[4.4975,2.7227,3.0513]}}";
  const char *bad = "{\"params\":{\"chi\":2,\"eta\":4,\"us\":0.0724,"
                    "\"ur\":0.6178,\"V\":1}}";
  const char *sim =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"initial\":[1.27,4.36,-0.8,1],\"t_end\":100,"
      "\"samples\":{\"n\":3000}}";
  const char *bat =
      "{\"requests\":[{\"path\":\"/orbit\",\"body\":{\"params\":{\"chi\":"
      "0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},\"guess\":{"
      "\"durations\":[4.4975,2.7227,3.0513]}}}]}";
  const char *cases[][3] = {{"/orbit", orbit, "200"},
                            {"/orbit", bad, "422"},
                            {"/simulate", sim, "200"},
                            {"/batch", bat, "200"}};
  for (int i = 0; i < 4; i++) {
    ASSERT_EQ_INT(raw_with(d.port, "POST", cases[i][0], mine, cases[i][1], &r),
                  0);
    ASSERT_EQ_INT(r.status, atoi(cases[i][2]));
    ASSERT_TRUE(has_header_line(r.raw, "Access-Control-Allow-Origin",
                                "http://app.example:3000"));
    ASSERT_TRUE(
        header_of(r.raw, "Access-Control-Expose-Headers", v, sizeof v) &&
        strstr(v, "X-Request-Id"));
    ASSERT_TRUE(has_header_line(r.raw, "Vary", "Origin"));
    http_free(&r);
    ASSERT_EQ_INT(raw_with(d.port, "POST", cases[i][0], other, cases[i][1], &r),
                  0);
    ASSERT_EQ_INT(r.status, atoi(cases[i][2]));
    ASSERT_TRUE(!header_of(r.raw, "Access-Control-Allow-Origin", v, sizeof v));
    ASSERT_TRUE(has_header_line(r.raw, "Vary", "Origin"));
    http_free(&r);
  }
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
  /* any origin, from the environment */
  setenv("STICKSLIP_CORS_ORIGIN", "*", 1);
  int rc = daemon_start(BIN, NULL, &d);
  unsetenv("STICKSLIP_CORS_ORIGIN");
  ASSERT_EQ_INT(rc, 0);
  ASSERT_EQ_INT(raw_with(d.port, "GET", "/health", other, NULL, &r), 0);
  ASSERT_TRUE(has_header_line(r.raw, "Access-Control-Allow-Origin", "*"));
  http_free(&r);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
  /* an origin with a path is refused at the start */
  const char *wrong[] = {"--cors-origin", "http://app.example/page", NULL};
  rc = daemon_start(BIN, wrong, &d);
  ASSERT_TRUE(rc != 0);
  if (rc == 0)
    daemon_stop(&d);
  unlink(d.log_path);
}

/* EVIDENCE: README "Operations": /metrics passes `promtool check metrics`
 * (Prometheus's own linter) after requests of every kind of status; skipped
 * where promtool is not installed (scripts/setup.sh --test installs it). */
static void test_promtool(void) {
  if (system("command -v promtool >/dev/null 2>&1") != 0) {
    printf("promtool: not installed, skipped\n");
    return;
  }
  daemon_proc d;
  ASSERT_EQ_INT(daemon_start(BIN, NULL, &d), 0);
  http_resp r;
  const char *const reqs[][3] = {
      {"GET", "/health", NULL},
      {"GET", "/nowhere", NULL},
      {"POST", "/orbit", "{}"},
      {"POST", "/orbit", "{"},
      {"GET", "/orbit", NULL},
      {"POST", "/stability",
       "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,"
       "\"ur\":0.6178,\"V\":1},\"phases\":[{\"mode\":"
       "\"slip\",\"duration\":4.4975},{\"mode\":"
       "\"overshoot\",\"duration\":2.7227},{\"mode\":"
       "\"stick\",\"duration\":3.0513}]}"}};
  for (size_t i = 0; i < sizeof reqs / sizeof reqs[0]; i++) {
    ASSERT_EQ_INT(http_do(d.port, reqs[i][0], reqs[i][1],
                          reqs[i][2] ? JSON : NULL, reqs[i][2], &r),
                  0);
    http_free(&r);
  }
  ASSERT_EQ_INT(http_do(d.port, "GET", "/metrics", NULL, NULL, &r), 0);
  char path[] = "/tmp/stickslip_metrics_XXXXXX";
  int fd = mkstemp(path);
  ASSERT_TRUE(fd >= 0);
  if (fd >= 0) {
    ASSERT_TRUE(write(fd, r.body, r.len) == (ssize_t)r.len);
    close(fd);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "promtool check metrics < %s", path);
    int rc = system(cmd);
    ASSERT_EQ_INT(rc, 0);
    printf("promtool check metrics: %s\n", rc == 0 ? "clean" : "FAILED");
    unlink(path);
  }
  ASSERT_TRUE(strstr(r.body, "code=\"404\"") &&
              strstr(r.body, "code=\"405\"") &&
              strstr(r.body, "code=\"422\"") && strstr(r.body, "code=\"400\""));
  http_free(&r);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* The tests that start their own daemon, by name. */
static const struct {
  const char *name;
  void (*run)(void);
} OWN_DAEMON[] = {
    {"flag_limits", test_flag_limits},
    {"time_limit", test_time_limit},
    {"connection_limits", test_connection_limits},
    {"pool", test_pool},
    {"shutdown", test_shutdown},
    {"slow_client", test_slow_client},
    {"memory", test_memory},
    {"forwarded", test_forwarded},
    {"batch", test_batch},
    {"environment", test_environment},
    {"promtool", test_promtool},
    {"cors", test_cors},
};

/* Usage: test_http PATH/stickslipd [NAME]: every test, or the one test
 * NAME of those that start their own daemon ("shared" for the rest). */
int main(int argc, char **argv) {
  daemon_proc d;
  if (argc < 2) {
    fprintf(stderr, "usage: %s PATH/stickslipd [test]\n", argv[0]);
    return 2;
  }
  signal(SIGPIPE, SIG_IGN);
  BIN = argv[1];
  const char *only = argc > 2 ? argv[2] : NULL;
  if (!only || !strcmp(only, "shared")) {
    ASSERT_EQ_INT(daemon_start(BIN, NULL, &d), 0);
    PORT = d.port;
    test_endpoints();
    test_spec_examples();
    test_map_against_orbit();
    test_operations(&d);
    test_gzip();
    test_explorer_files();
    test_orbit_curves();
    test_bad_input();
    test_framing();
    ASSERT_EQ_INT(daemon_stop(&d), 0);
    unlink(d.log_path);
  }
  for (size_t i = 0; i < sizeof OWN_DAEMON / sizeof OWN_DAEMON[0]; i++)
    if (!only || !strcmp(only, OWN_DAEMON[i].name))
      OWN_DAEMON[i].run();
  TEST_DONE();
}
