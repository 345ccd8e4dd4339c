/*
 * test_http_operations.c (CTest http_operations): X-Request-Id, the access
 * log, validators, /metrics (and promtool on it), --health-check, and the
 * options from the environment.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "fixture.h"

static int is_hex16(const char *s) {
  if (!s || strlen(s) != 16)
    return 0;
  for (int i = 0; i < 16; i++)
    if (!strchr("0123456789abcdef", s[i]))
      return 0;
  return 1;
}

/* EVIDENCE: docs/howto/operations.md: X-Request-Id taken or made, echoed in the
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

/* EVIDENCE: docs/howto/operations.md: every option from the environment, the
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

/* EVIDENCE: docs/howto/operations.md: /metrics passes `promtool check metrics`
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

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_operations(&d);
  fixture_daemon_stop(&d);
  test_environment();
  test_promtool();
  TEST_DONE();
}
