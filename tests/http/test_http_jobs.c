/*
 * test_http_jobs.c (CTest http_jobs): jobs over HTTP (Prefer:
 * respond-async, /jobs), on a throwaway sqlite store: the statuses a job
 * goes through, its results equal to the synchronous answer, progress,
 * results streamed while the job runs and ?wait=false, a daemon killed
 * with SIGKILL and started again on the same store, a dismissal that stops
 * the work at once, ids unknown and malformed, and a store that cannot be
 * used, which leaves synchronous requests alone.
 */
#define _GNU_SOURCE
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "fixture.h"

#define ASYNC "Prefer: handling=lenient, RESPOND-ASYNC; wait=5\r\n"
#define ORBIT "{" PAPER ",\"kind\":\"overshoot\"}"
/* a /simulate of a few hundredths of a second */
#define SLOW "{" PAPER ",\"initial\":" X0 ",\"t_end\":4e5,\"events\":false}"
/* ... and one of more than half a second */
#define SECONDS_SIM                                                            \
  "{" PAPER ",\"initial\":" X0 ",\"t_end\":9e6,\"events\":false}"

static char TMP[64];
/* How long a job of the test batch may take: 30 s, or 8 times the same
 * batch answered synchronously when that is longer (a job computes on one
 * worker where the synchronous batch uses the pool, and the sanitizers on a
 * loaded machine slow both many times). */
static double BATCH_SECONDS = 30;

#define ASSERT_STR_EQ(a, b)                                                    \
  do {                                                                         \
    const char *a_ = (a), *b_ = (b);                                           \
    test_checks_++;                                                            \
    if (!a_ || !b_ || strcmp(a_, b_))                                          \
      TEST_FAIL_("%s is \"%.300s\", want \"%.300s\"", #a, a_ ? a_ : "(null)",  \
                 b_ ? b_ : "(null)");                                          \
  } while (0)

/* A request with @a headers (lines ending in CRLF) and a body of any
 * size. */
static int req(int port, const char *method, const char *path,
               const char *headers, const char *body, http_resp *r) {
  size_t blen = body ? strlen(body) : 0, cap = blen + strlen(headers) + 512;
  char *q = malloc(cap);
  int k = snprintf(q, cap,
                   "%s %s HTTP/1.1\r\nHost: t\r\nConnection: close\r\n%s%s"
                   "Content-Length: %zu\r\n\r\n%s",
                   method, path, headers,
                   body ? "Content-Type: application/json\r\n" : "", blen,
                   body ? body : "");
  int rc = http_raw(port, q, (size_t)k, r);
  free(q);
  return rc;
}

/* A batch of @a n items of @a item on @a path. */
static char *batch_of(int n, const char *path, const char *item) {
  size_t cap = (size_t)n * (strlen(item) + 64) + 64, k = 0;
  char *b = malloc(cap);
  k += (size_t)snprintf(b, cap, "{\"requests\":[");
  for (int i = 0; i < n; i++)
    k += (size_t)snprintf(b + k, cap - k,
                          "%s{\"id\":%d,\"path\":\"%s\",\"body\":%s}",
                          i ? "," : "", i, path, item);
  snprintf(b + k, cap - k, "]}");
  return b;
}

/* EVIDENCE: RFC 7240 and OGC API - Processes: a computing POST that
 * prefers respond-async (a token among others, in any case, with
 * parameters) is answered 201, Location: /jobs/{id}, Preference-Applied
 * and the job's status, accepted. */
static void submit(int port, const char *path, const char *body, char *id) {
  http_resp r;
  char loc[128] = "", pa[64] = "";
  id[0] = 0;
  ASSERT_EQ_INT(req(port, "POST", path, ASYNC, body, &r), 0);
  ASSERT_EQ_INT(r.status, 201);
  ASSERT_TRUE(header_of(r.raw, "Location", loc, sizeof loc) &&
              !strncmp(loc, "/jobs/", 6) && strlen(loc) == 6 + 32);
  ASSERT_TRUE(header_of(r.raw, "Preference-Applied", pa, sizeof pa) &&
              !strcmp(pa, "respond-async"));
  json_t *j = json_loads(r.body, 0, NULL);
  ASSERT_TRUE(j != NULL);
  ASSERT_STR_EQ(json_string_value(json_object_get(j, "status")), "accepted");
  ASSERT_STR_EQ(json_string_value(json_object_get(j, "id")), loc + 6);
  ASSERT_STR_EQ(json_string_value(json_object_get(j, "path")), path);
  snprintf(id, 33, "%.32s", loc + 6);
  json_decref(j);
  http_free(&r);
}

static json_t *status_of(int port, const char *id) {
  http_resp r;
  char path[64];
  snprintf(path, sizeof path, "/jobs/%s", id);
  if (http_do(port, "GET", path, NULL, NULL, &r) != 0)
    return NULL;
  json_t *j = r.status == 200 ? json_loads(r.body, 0, NULL) : NULL;
  http_free(&r);
  return j;
}

static const char *status_str(json_t *j) {
  const char *s = json_string_value(json_object_get(j, "status"));
  return s ? s : "?";
}

/* Poll job @a id until it is finished (or @a seconds pass): its last
 * status.  EVIDENCE: docs/api/jobs.md: progress 0-100, monotone; a job goes
 * accepted -> running -> successful (*running: running was seen). */
static json_t *until_done(int port, const char *id, double seconds,
                          int *running) {
  double t0 = mono(), last = -1;
  json_t *j = NULL;
  while (mono() - t0 < seconds) {
    json_decref(j);
    j = status_of(port, id);
    if (!j)
      break;
    double p = num(j, "/progress");
    ASSERT_TRUE(p >= last && p <= 100);
    last = p;
    const char *s = status_str(j);
    if (running && !strcmp(s, "running"))
      *running = 1;
    if (strcmp(s, "accepted") && strcmp(s, "running"))
      return j;
    usleep(20000);
  }
  TEST_FAIL_("job %s not finished within %g s", id, seconds);
  return j;
}

static char *results(int port, const char *id, const char *query, int *status,
                     char *ctype) {
  http_resp r;
  char path[96];
  snprintf(path, sizeof path, "/jobs/%s/results%s", id, query);
  if (http_do(port, "GET", path, NULL, NULL, &r) != 0)
    return NULL;
  *status = r.status;
  if (ctype)
    snprintf(ctype, 96, "%s", r.ctype);
  char *b = strdup(r.body);
  http_free(&r);
  return b;
}

/* The NDJSON lines of a batch's answer, item lines sorted by their index
 * and the done line without its "seconds", as one text. */
static int by_index(const void *a, const void *b) {
  json_t *x = json_loads(*(char *const *)a, 0, NULL);
  json_t *y = json_loads(*(char *const *)b, 0, NULL);
  double d = num(x, "/index") - num(y, "/index");
  json_decref(x);
  json_decref(y);
  return d < 0 ? -1 : d > 0;
}

static char *canonical(const char *ndjson, int *items) {
  char *copy = strdup(ndjson), *save, *lines[4096];
  int n = 0;
  char *done = NULL;
  for (char *l = strtok_r(copy, "\n", &save); l && n < 4096;
       l = strtok_r(NULL, "\n", &save)) {
    if (strstr(l, "\"done\":true"))
      done = l;
    else
      lines[n++] = l;
  }
  qsort(lines, (size_t)n, sizeof *lines, by_index);
  size_t cap = strlen(ndjson) + 64, k = 0;
  char *out = calloc(1, cap);
  for (int i = 0; i < n; i++)
    k += (size_t)snprintf(out + k, cap - k, "%s\n", lines[i]);
  if (done) {
    json_t *d = json_loads(done, 0, NULL);
    json_object_del(d, "seconds");
    char *t = json_dumps(d, JSON_SORT_KEYS | JSON_COMPACT);
    snprintf(out + k, cap - k, "%s\n", t);
    free(t);
    json_decref(d);
  }
  *items = n;
  free(copy);
  return out;
}

/* Whether each of the @a n items' indexes is there exactly once. */
static int each_once(const char *ndjson, int n) {
  int *seen = calloc((size_t)n, sizeof *seen), ok = 1;
  for (const char *p = strstr(ndjson, "\"index\":"); p;
       p = strstr(p + 1, "\"index\":")) {
    int i = atoi(p + 8);
    if (i < 0 || i >= n || seen[i]++)
      ok = 0;
  }
  for (int i = 0; i < n; i++)
    ok = ok && seen[i] == 1;
  free(seen);
  return ok;
}

static char *sync_answer(int port, const char *path, const char *body) {
  http_resp r;
  if (http_do(port, "POST", path, JSON, body, &r) != 0)
    return NULL;
  ASSERT_EQ_INT(r.status, 200);
  char *b = strdup(r.body);
  http_free(&r);
  return b;
}

static void wait_for(int port, const char *id, const char *what, long min) {
  for (double t0 = mono(); mono() - t0 < BATCH_SECONDS;) {
    json_t *j = status_of(port, id);
    long done = (long)num(j, "/items/done");
    int running = !strcmp(status_str(j), "running");
    json_decref(j);
    if (!strcmp(what, "items") ? done >= min : running)
      return;
    usleep(20000);
  }
  TEST_FAIL_("job %s: %ld %s not done in time", id, min, what);
}

/* EVIDENCE: the central rule of jobs (stickslip_api.h, Jobs): a job's
 * results are the synchronous answer: /orbit byte for byte, /batch line by
 * line (but the done line's seconds; a synchronous batch writes its lines
 * in the order they are done). */
static void test_single_and_batch(int port, const char *batch,
                                  const char *want) {
  char id[33], ctype[96];
  int st, running = 0, n;
  submit(port, "/orbit", ORBIT, id);
  json_decref(until_done(port, id, 20, NULL));
  char *got = results(port, id, "", &st, ctype);
  char *sync = sync_answer(port, "/orbit", ORBIT);
  ASSERT_EQ_INT(st, 200);
  ASSERT_STR_EQ(ctype, "application/json");
  ASSERT_TRUE(got && sync && !strcmp(got, sync));
  free(got);
  free(sync);
  submit(port, "/batch", batch, id);
  json_t *j = until_done(port, id, BATCH_SECONDS, &running);
  ASSERT_STR_EQ(status_str(j), "successful");
  ASSERT_TRUE(running);
  ASSERT_EQ_INT((int)num(j, "/progress"), 100);
  ASSERT_TRUE(num(j, "/items/done") == num(j, "/items/total"));
  json_decref(j);
  got = results(port, id, "", &st, ctype);
  ASSERT_EQ_INT(st, 200);
  ASSERT_STR_EQ(ctype, "application/x-ndjson");
  char *c = canonical(got, &n);
  ASSERT_STR_EQ(c, want);
  free(c);
  free(got);
}

/* The time the first item line of job @a id's results arrives, read as it
 * streams; the whole stream into *all. */
static double first_line(int port, const char *id, char **all) {
  char reqs[160];
  snprintf(reqs, sizeof reqs,
           "GET /jobs/%s/results HTTP/1.1\r\nHost: t\r\nConnection: "
           "close\r\n\r\n",
           id);
  int fd = http_send(port, reqs, strlen(reqs));
  size_t cap = 1 << 20, n = 0;
  char *b = malloc(cap);
  double first = -1;
  struct pollfd p = {fd, POLLIN, 0};
  while (fd >= 0 && poll(&p, 1, 20000) == 1) {
    ssize_t k = recv(fd, b + n, cap - n - 1, 0);
    if (k <= 0)
      break;
    n += (size_t)k;
    b[n] = 0;
    if (first < 0 && strstr(b, "\"index\":"))
      first = mono();
  }
  if (fd >= 0)
    close(fd);
  *all = b;
  return first;
}

/* EVIDENCE: docs/api/jobs.md: the results of a running /batch job stream:
 * lines come before the job ends; ?wait=false gives the lines stored and
 * ends at once. */
static void test_stream(int port, const char *batch, int items) {
  char id[33];
  int st;
  submit(port, "/batch", batch, id);
  wait_for(port, id, "items", 1);
  double t0 = mono();
  char *part = results(port, id, "?wait=false", &st, NULL);
  ASSERT_TRUE(mono() - t0 < 1.0);
  ASSERT_EQ_INT(st, 200);
  int lines = 0;
  for (const char *p = part; p && (p = strchr(p, '\n')); p++)
    lines++;
  ASSERT_TRUE(lines >= 1 && lines < items + 1);
  ASSERT_TRUE(part && (!*part || part[strlen(part) - 1] == '\n'));
  free(part);
  char *all;
  double first = first_line(port, id, &all);
  ASSERT_TRUE(first > 0);
  json_t *j = until_done(port, id, BATCH_SECONDS, NULL);
  ASSERT_STR_EQ(status_str(j), "successful");
  json_decref(j);
  double done = mono();
  ASSERT_TRUE(first < done - 0.2);
  ASSERT_TRUE(strstr(all, "\"done\":true") != NULL);
  free(all);
}

/* EVIDENCE: docs/api/jobs.md: DELETE of a running job: 200 with its status
 * dismissed, its results gone (404), and the daemon's CPU back to idle:
 * busy before (over a tenth of a core), and under a tenth of a core in the
 * half second that starts 100 ms after the DELETE's answer (the kernel
 * counts CPU in ticks of 10 ms: the window is long enough to see it). */
static void test_dismiss(const daemon_proc *d, const char *batch) {
  char id[33], path[64];
  http_resp r;
  int st;
  submit(d->port, "/batch", batch, id);
  wait_for(d->port, id, "running", 0);
  double c0 = cpu_seconds(d->pid), t0 = mono();
  usleep(300000);
  double busy = (cpu_seconds(d->pid) - c0) / (mono() - t0);
  /* computing: a tenth of a core at least, which a loaded machine still
   * gives it (alone it takes a whole one) */
  ASSERT_TRUE(busy > 0.1);
  snprintf(path, sizeof path, "/jobs/%s", id);
  ASSERT_EQ_INT(http_do(d->port, "DELETE", path, NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(strstr(r.body, "\"dismissed\"") != NULL);
  http_free(&r);
  usleep(100000);
  c0 = cpu_seconds(d->pid);
  t0 = mono();
  usleep(500000);
  double idle = (cpu_seconds(d->pid) - c0) / (mono() - t0);
  if (idle >= 0.1)
    TEST_FAIL_("CPU after DELETE: %.2f of a core (before: %.2f)", idle, busy);
  test_checks_++;
  json_t *j = status_of(d->port, id);
  ASSERT_STR_EQ(status_str(j), "dismissed");
  json_decref(j);
  free(results(d->port, id, "", &st, NULL));
  ASSERT_EQ_INT(st, 404);
}

/* EVIDENCE: docs/api/jobs.md: malformed ids 400, unknown 404
 * (problem+json); the list's paging parameters checked; the list newest
 * first. */
static void test_ids(int port) {
  const char *zero = "00000000000000000000000000000000";
  char path[96];
  json_decref(expect_problem("short id", "GET", "/jobs/0123", NULL, NULL, 400,
                             "/problems/bad-request", NULL));
  json_decref(expect_problem("upper id", "GET",
                             "/jobs/0000000000000000000000000000000A", NULL,
                             NULL, 400, "/problems/bad-request", NULL));
  snprintf(path, sizeof path, "/jobs/%s", zero);
  json_decref(expect_problem("unknown", "GET", path, NULL, NULL, 404,
                             "/problems/not-found", 0));
  json_decref(expect_problem("unknown delete", "DELETE", path, NULL, NULL, 404,
                             "/problems/not-found", NULL));
  snprintf(path, sizeof path, "/jobs/%s/results", zero);
  json_decref(expect_problem("unknown results", "GET", path, NULL, NULL, 404,
                             "/problems/not-found", NULL));
  json_decref(expect_problem("other", "GET", "/jobs/x/y/z", NULL, NULL, 404,
                             "/problems/not-found", NULL));
  json_decref(expect_problem("post", "POST", "/jobs", JSON, "{}", 405,
                             "/problems/method-not-allowed", NULL));
  json_t *p = expect_problem("limit", "GET", "/jobs?limit=0", NULL, NULL, 400,
                             "/problems/bad-request", NULL);
  ASSERT_TRUE(p &&
              strstr(json_string_value(json_object_get(p, "detail")), "limit"));
  json_decref(p);
  p = expect_problem("offset", "GET", "/jobs?offset=x", NULL, NULL, 400,
                     "/problems/bad-request", NULL);
  ASSERT_TRUE(
      p && strstr(json_string_value(json_object_get(p, "detail")), "offset"));
  json_decref(p);
  http_resp r;
  ASSERT_EQ_INT(http_do(port, "GET", "/jobs?limit=2", NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  json_t *l = json_loads(r.body, 0, NULL);
  json_t *jobs = json_object_get(l, "jobs");
  ASSERT_EQ_INT((int)json_array_size(jobs), 2);
  ASSERT_TRUE(num(l, "/total") >= 4);
  ASSERT_TRUE(strcmp(json_string_value(
                         json_object_get(json_array_get(jobs, 0), "created")),
                     json_string_value(json_object_get(json_array_get(jobs, 1),
                                                       "created"))) >= 0);
  json_decref(l);
  http_free(&r);
}

/* EVIDENCE: docs/api/jobs.md: a job is bound by --job-max-seconds; a job
 * whose chunk fails is failed, with its message, and its results are its
 * problem with its status. */
static void test_failed(void) {
  daemon_proc d;
  char store[128], id[33];
  int st;
  snprintf(store, sizeof store, "sqlite:%s/failed.sqlite", TMP);
  const char *args[] = {"--job-store", store,     "--job-max-seconds",
                        "0.1",         "--quiet", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  submit(d.port, "/simulate", SECONDS_SIM, id);
  json_t *j = until_done(d.port, id, 20, NULL);
  ASSERT_STR_EQ(status_str(j), "failed");
  ASSERT_TRUE(json_string_length(json_object_get(j, "message")) > 0);
  json_decref(j);
  char *b = results(d.port, id, "", &st, NULL);
  ASSERT_EQ_INT(st, 422);
  ASSERT_TRUE(b && strstr(b, "/problems/limit-exceeded"));
  free(b);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* EVIDENCE: docs/api/jobs.md: a daemon killed with SIGKILL mid-job and
 * started again on the same store finishes the job: every item once, the
 * same answer as an uninterrupted run. */
static void test_kill(const char *batch, int items, const char *want) {
  daemon_proc d;
  char store[128], id[33], lease_s[8] = "1";
  snprintf(store, sizeof store, "sqlite:%s/kill.sqlite", TMP);
  const char *args[] = {"--job-store", store,     "--job-lease",
                        lease_s,       "--quiet", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  submit(d.port, "/batch", batch, id);
  wait_for(d.port, id, "items", 1);
  json_t *j = status_of(d.port, id);
  ASSERT_TRUE(num(j, "/items/done") < items);
  json_decref(j);
  kill(d.pid, SIGKILL);
  waitpid(d.pid, NULL, 0);
  unlink(d.log_path);
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  j = until_done(d.port, id, BATCH_SECONDS, NULL);
  ASSERT_STR_EQ(status_str(j), "successful");
  json_decref(j);
  int st, n;
  char *got = results(d.port, id, "", &st, NULL);
  ASSERT_EQ_INT(st, 200);
  ASSERT_TRUE(got && each_once(got, items));
  char *c = canonical(got, &n);
  ASSERT_STR_EQ(c, want);
  free(c);
  free(got);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* EVIDENCE: docs/api/jobs.md: a store that cannot be used gives 503
 * store-unavailable with Retry-After to new jobs, while synchronous
 * requests are served: one that cannot be opened at the start, and one
 * whose file is deleted under the daemon. */
static void expect_unavailable(int port, const char *what) {
  http_resp r;
  ASSERT_EQ_INT(req(port, "POST", "/orbit", ASYNC, ORBIT, &r), 0);
  if (r.status != 503 || !strstr(r.body, "/problems/store-unavailable") ||
      !r.retry_after[0])
    TEST_FAIL_("%s: a job got %d: %.200s", what, r.status, r.body);
  test_checks_++;
  http_free(&r);
  ASSERT_EQ_INT(req(port, "POST", "/orbit", "", ORBIT, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
}

static void test_unavailable(const char *deleted) {
  daemon_proc d;
  const char *args[] = {"--job-store", "sqlite:/dev/null/no/jobs.sqlite",
                        "--quiet", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  expect_unavailable(d.port, "a store that cannot be opened");
  char *log = daemon_log(&d);
  ASSERT_TRUE(log && strstr(log, "cannot be opened"));
  free(log);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
  const char *args2[] = {"--job-store", deleted, "--quiet", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args2, &d), 0);
  char file[160];
  snprintf(file, sizeof file, "%s", deleted + 7);
  ASSERT_EQ_INT(unlink(file), 0);
  expect_unavailable(d.port, "a store whose file is deleted");
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* EVIDENCE: docs/api/jobs.md: a /batch job takes up to --max-job-items items,
 * past the synchronous --max-batch-items; more are refused at submission
 * with the limit's name. */
static void test_job_items(void) {
  daemon_proc d;
  char store[128];
  http_resp r;
  snprintf(store, sizeof store, "sqlite:%s/items.sqlite", TMP);
  const char *args[] = {"--job-store",     store, "--max-batch-items", "4",
                        "--max-job-items", "6",   "--quiet",           NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  char *six = batch_of(6, "/orbit", ORBIT),
       *seven = batch_of(7, "/orbit", ORBIT);
  ASSERT_EQ_INT(req(d.port, "POST", "/batch", "", six, &r), 0);
  ASSERT_EQ_INT(r.status, 422); /* synchronous: over --max-batch-items */
  http_free(&r);
  ASSERT_EQ_INT(req(d.port, "POST", "/batch", ASYNC, six, &r), 0);
  ASSERT_EQ_INT(r.status, 201);
  http_free(&r);
  ASSERT_EQ_INT(req(d.port, "POST", "/batch", ASYNC, seven, &r), 0);
  ASSERT_EQ_INT(r.status, 422);
  ASSERT_TRUE(strstr(r.body, "max_batch_items") != NULL ||
              strstr(r.body, "max_job_items") != NULL);
  http_free(&r);
  free(six);
  free(seven);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

int main(int argc, char **argv) {
  int rc = fixture_init(argc, argv);
  if (rc)
    return rc;
  snprintf(TMP, sizeof TMP, "/tmp/stickslip-jobs-XXXXXX");
  ASSERT_TRUE(mkdtemp(TMP) != NULL);
  daemon_proc d;
  char store[128];
  snprintf(store, sizeof store, "sqlite:%s/jobs.sqlite", TMP);
  const char *args[] = {"--job-store", store, "--quiet", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;
  const int items = 128; /* four chunks of 32 and the done line */
  char *batch = batch_of(items, "/simulate", SLOW);
  double t0 = mono();
  char *sync = sync_answer(d.port, "/batch", batch);
  if (8 * (mono() - t0) > BATCH_SECONDS)
    BATCH_SECONDS = 8 * (mono() - t0);
  int n;
  char *want = canonical(sync ? sync : "", &n);
  ASSERT_EQ_INT(n, items);
  test_single_and_batch(d.port, batch, want);
  test_stream(d.port, batch, items);
  test_dismiss(&d, batch);
  test_ids(d.port);
  fixture_daemon_stop(&d);
  test_failed();
  test_job_items();
  test_kill(batch, items, want);
  snprintf(store, sizeof store, "sqlite:%s/deleted.sqlite", TMP);
  test_unavailable(store);
  free(sync);
  free(want);
  free(batch);
  char cmd[96];
  snprintf(cmd, sizeof cmd, "rm -rf %s", TMP);
  if (system(cmd) != 0)
    fprintf(stderr, "could not remove %s\n", TMP);
  TEST_DONE();
}
