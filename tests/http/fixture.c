/*
 * fixture.c: see fixture.h.
 */
#define _GNU_SOURCE
#include "fixture.h"

#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* test.h's counters, one pair for the executable (TEST_SHARED_COUNTERS) */
int test_failures_, test_checks_;

const char *BIN;
int PORT;

int fixture_init(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: %s PATH/stickslipd\n", argv[0]);
    return 2;
  }
  signal(SIGPIPE, SIG_IGN);
  BIN = argv[1];
  return 0;
}

void fixture_daemon_start(daemon_proc *d) {
  ASSERT_EQ_INT(daemon_start(BIN, NULL, d), 0);
  PORT = d->port;
}

void fixture_daemon_stop(daemon_proc *d) {
  ASSERT_EQ_INT(daemon_stop(d), 0);
  unlink(d->log_path);
}

json_t *post(const char *path, const char *body, int want) {
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

double num(json_t *j, const char *path) {
  /* a tiny JSON pointer: /a/0/b */
  char buf[256], *save, *tok;
  snprintf(buf, sizeof buf, "%s", path);
  for (tok = strtok_r(buf, "/", &save); tok && j;
       tok = strtok_r(NULL, "/", &save))
    j = json_is_array(j) ? json_array_get(j, (size_t)atoi(tok))
                         : json_object_get(j, tok);
  return j && json_is_number(j) ? json_number_value(j) : NAN;
}

void health_ok(const char *after) {
  http_resp r;
  int rc = http_do(PORT, "GET", "/health", NULL, NULL, &r);
  if (rc != 0 || r.status != 200 || !strstr(r.body, "\"ok\""))
    TEST_FAIL_("/health after %s: rc %d status %d: %.200s", after, rc, r.status,
               rc == 0 ? r.body : "");
  test_checks_++;
  http_free(&r);
}

/* EVIDENCE: docs/api/errors.md: bad input gets an application/problem+json
 * body with type, title, status, detail and, where a field is at fault, its
 * pointer.  The problem body of @a r, or NULL after a failure. */
json_t *problem_body(const char *name, const http_resp *r, int want,
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
void expect_problem_raw(const char *name, const char *raw, size_t len, int want,
                        const char *type, int mhd_page) {
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
json_t *expect_problem(const char *name, const char *method, const char *path,
                       const char *ctype, const char *body, int want,
                       const char *type, const char *pointer) {
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

/* Computations for the pool tests: LONG needs minutes (it ends only by
 * cancellation or shutdown), MEDIUM about a second, CHEAP microseconds. */
const char *const LONG_SIM =
    "{" PAPER ",\"initial\":" X0 ",\"t_end\":9e8,\"events\":false}";
const char *const MEDIUM_SIM =
    "{" PAPER ",\"initial\":" X0 ",\"t_end\":1.5e7,\"events\":false}";
const char *const CHEAP =
    "{" PAPER ",\"phases\":[{\"mode\":\"slip\",\"duration\":4.497497290813434},"
    "{\"mode\":\"overshoot\",\"duration\":2.7226655903272814},{\"mode\":"
    "\"stick\",\"duration\":3.05126697421287}],\"z0\":[1.1834277342427062,"
    "3.910427734242709,-0.8074871367243069,1.0]}";

double mono(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Send a POST and return the socket to read the answer from. */
int start(int port, const char *path, const char *body) {
  size_t len;
  char *req = http_request("POST", path, JSON, body, &len);
  int fd = http_send(port, req, len);
  free(req);
  return fd;
}

/* A counter of the daemon's /metrics, or -1. */
double metric(int port, const char *name) {
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
double cpu_seconds(pid_t pid) {
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

void *cheap_probe(void *vp) {
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

/* Structural equality with a relative tolerance on numbers. */
int same_json(json_t *a, json_t *b, double rtol, char *where, size_t n) {
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

/* The value of header @a name in the raw response @a raw (into @a out), or
 * NULL. */
const char *header_of(const char *raw, const char *name, char *out, size_t n) {
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
int raw_with(int port, const char *method, const char *path,
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
