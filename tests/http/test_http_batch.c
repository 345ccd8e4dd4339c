/*
 * test_http_batch.c (CTest http_batch): POST /batch through HTTP: an NDJSON
 * line per item as it is done, bad items answered by their own lines, the
 * batch refused as a whole, a hang-up and a shutdown mid-batch, and every
 * path an item may ask answered on one line as it is alone.
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
#include <unistd.h>

#include "fixture.h"

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

/* EVIDENCE: docs/api/batch.md: an NDJSON line per item as it is done, a bad
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

/* The answer to @a body posted alone to @a path, as JSON: an NDJSON answer
 * as the array of its lines; NULL after a failure. */
static json_t *alone(const char *path, const char *body) {
  http_resp r;
  json_t *j = NULL;
  if (http_do(PORT, "POST", path, JSON, body, &r) != 0 || r.status != 200) {
    TEST_FAIL_("POST %s alone: no 200", path);
    http_free(&r);
    return NULL;
  }
  if (strcmp(r.ctype, "application/x-ndjson") != 0) {
    j = json_loadb(r.body, r.len, 0, NULL);
  } else {
    j = json_array();
    for (char *a = r.body, *e; (e = strchr(a, '\n')); a = e + 1)
      json_array_append_new(j, json_loadb(a, (size_t)(e - a), 0, NULL));
  }
  http_free(&r);
  return j;
}

/* The lines of an NDJSON answer with their "seconds" (a /map's last line:
 * the time it took) left out. */
static void drop_seconds(json_t *lines) {
  size_t i;
  json_t *l;
  json_array_foreach(lines, i, l) json_object_del(l, "seconds");
}

/* The paths an item may ask, as a refused item's problem lists them:
 * "..., an item may ask /orbit, /simulate, ...". */
static void paths_allowed(const ndjson *nd, int index, char *out, size_t n) {
  const char *d = str_at(item_line(nd, index), "body", "detail");
  const char *at = strstr(d, "may ask ");
  snprintf(out, n, "%s", at ? at + 8 : "");
}

/* EVIDENCE: docs/api/batch.md: every path an item may ask, /map
 * included, answered on one line of the batch (a /map's lines as an array),
 * with the body it gets alone */
static void test_every_path(void) {
  static const struct {
    const char *path, *body;
  } items[] = {
      {"/orbit", "{" PAPER ",\"guess\":{\"durations\":[4.5,2.717,3.0536]}}"},
      {"/simulate", "{" PAPER ",\"initial\":" X0 ",\"t_end\":10.27}"},
      {"/stability", NULL /* CHEAP */},
      {"/continue",
       "{" PAPER ",\"guess\":{\"durations\":[4.4975,2.7227,3.0513]},"
       "\"parameter\":\"ur\",\"range\":[0.3,1.5],\"direction\":\"down\"}"},
      {"/map", "{" PAPER ",\"axes\":[{\"parameter\":\"ur\",\"from\":0.55,"
               "\"to\":0.75,\"n\":5}],\"kind\":\"overshoot\"}"},
      {"/map", "{" PAPER ",\"axes\":[{\"parameter\":\"ur\",\"from\":0.65,"
               "\"to\":0.75,\"n\":2}],\"kind\":\"overshoot\",\"fields\":"
               "[\"period\",\"multipliers\",\"marginal\"]}"},
      {"/basins",
       "{" PAPER ",\"axes\":[{\"variable\":\"x1\",\"from\":-2,\"to\":4,"
       "\"n\":6},{\"variable\":\"x2\",\"from\":0,\"to\":8,\"n\":6}],"
       "\"state\":{\"v1\":0,\"v2\":1}}"},
  };
  enum { N = sizeof items / sizeof items[0] };
  daemon_proc d;
  fixture_daemon_start(&d);
  char body[8192], list[256] = "";
  size_t k = (size_t)snprintf(body, sizeof body, "{\"requests\":[");
  for (int i = 0; i < N; i++)
    k += (size_t)snprintf(body + k, sizeof body - k,
                          "{\"id\":%d,\"path\":\"%s\",\"body\":%s},", i,
                          items[i].path, items[i].body ? items[i].body : CHEAP);
  /* an item that is refused, whose problem lists the paths an item may ask */
  snprintf(body + k, sizeof body - k, "{\"path\":\"/health\",\"body\":{}}]}");
  int fd = start(d.port, "/batch", body);
  ndjson nd;
  read_ndjson(fd, 120000, 0, &nd); /* fails on a line that is not JSON */
  close(fd);
  ASSERT_EQ_INT(nd.status, 200);
  ASSERT_TRUE(nd.complete);
  ASSERT_EQ_INT(nd.n, N + 2);
  for (int i = 0; i < nd.n; i++)
    ASSERT_TRUE(json_is_object(nd.line[i]));
  ASSERT_TRUE(json_is_true(json_object_get(nd.line[nd.n - 1], "done")));
  ASSERT_EQ_INT(
      (int)json_integer_value(json_object_get(nd.line[nd.n - 1], "ok")), N);

  /* every path allowed is among the items */
  paths_allowed(&nd, N, list, sizeof list);
  ASSERT_TRUE(list[0] != 0);
  for (char *p = list, *e; *p; p = e + (*e ? 2 : 0)) {
    e = p + strcspn(p, ",");
    int found = 0;
    for (int i = 0; i < N; i++)
      found |= strlen(items[i].path) == (size_t)(e - p) &&
               !strncmp(items[i].path, p, (size_t)(e - p));
    if (!found)
      TEST_FAIL_("an item may ask %.*s, which the test does not send",
                 (int)(e - p), p);
    test_checks_++;
  }

  /* each item's body is the answer to its request alone */
  for (int i = 0; i < N; i++) {
    json_t *l = item_line(&nd, i);
    ASSERT_TRUE(l != NULL);
    if (!l)
      continue;
    ASSERT_EQ_INT((int)json_integer_value(json_object_get(l, "status")), 200);
    json_t *want = alone(items[i].path, items[i].body ? items[i].body : CHEAP);
    json_t *got = json_object_get(l, "body");
    ASSERT_TRUE(want != NULL);
    if (!want)
      continue;
    if (json_is_array(want)) {
      ASSERT_TRUE(json_is_array(got));
      drop_seconds(want);
      drop_seconds(got);
    }
    char where[256] = "";
    if (!same_json(want, got, 0, where, sizeof where))
      TEST_FAIL_("the %s item differs from the request alone at %s",
                 items[i].path, where);
    test_checks_++;
    json_decref(want);
  }
  printf("batch: %d items, one per path (%s), %d lines, each one JSON "
         "object\n",
         N, list, nd.n);
  ndjson_free(&nd);
  fixture_daemon_stop(&d);
}

int main(int argc, char **argv) {
  if (fixture_init(argc, argv))
    return 2;
  test_batch();
  test_every_path();
  TEST_DONE();
}
