/*
 * test_jobs.c: requests served as jobs (api_job_*) against the same
 * requests served synchronously (api_handle), without a server: the cuts,
 * the answers made of the chunks' results whatever order the chunks of a
 * stage run in, the problems at submission, and the status documents.
 * Usage: test_jobs CASES_DIR
 */
#define _POSIX_C_SOURCE 200809L
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "job_runner.h"
#include "stickslip.h"
#include "stickslip_api.h"
#include "test.h"

static const char *cases_dir;

static size_t endpoint(const char *path) {
  size_t ep = api_endpoint_count();
  ASSERT_EQ_INT(api_route("POST", path, &ep), 200);
  return ep;
}

/* The request of codec case @a name (malloc'd). */
static char *case_request(const char *name, size_t *len) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s/request.json", cases_dir, name);
  FILE *f = fopen(path, "rb");
  char *b = NULL;
  long n;
  if (f && fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 &&
      fseek(f, 0, SEEK_SET) == 0 && (b = malloc((size_t)n + 1)) &&
      fread(b, 1, (size_t)n, f) == (size_t)n) {
    b[n] = 0;
    *len = (size_t)n;
  } else {
    free(b);
    b = NULL;
    TEST_FAIL_("cannot read %s", path);
  }
  if (f)
    fclose(f);
  return b;
}

/* The job's answer, in @a order, is the synchronous one but for "seconds";
 * returns the trace. */
static job_trace same_answer(const char *what, size_t ep, const char *body,
                             size_t len, const api_limits *lim, job_order order,
                             unsigned seed) {
  api_response s, r;
  job_trace t;
  api_handle(ep, body, len, lim, NULL, &s);
  job_answer(ep, body, len, lim, order, seed, &r, &t);
  char *a = job_blank(s.body, s.len, "seconds");
  char *b = job_blank(r.body ? r.body : "", r.len, "seconds");
  test_checks_++;
  if (r.status != s.status || strcmp(a, b) ||
      strcmp(r.content_type, s.content_type))
    TEST_FAIL_("%s (order %d): the job answers %d %s\n%.3000s\nthe request "
               "%d %s\n%.3000s",
               what, (int)order, r.status, r.content_type, b, s.status,
               s.content_type, a);
  ASSERT_EQ_INT(t.bad_reads, 0);
  ASSERT_EQ_INT(t.items, t.items_sum);
  free(a);
  free(b);
  api_response_free(&s);
  api_response_free(&r);
  return t;
}

/* EVIDENCE: stickslip_api.h "Jobs": a single answer is one visible chunk,
 * and the job answers what the request answers */
static void test_single_answers(void) {
  static const struct {
    const char *path, *name;
  } CASES[] = {
      {"/orbit", "orbit-paper-guess"},
      {"/orbit", "orbit-physical-units"},
      {"/simulate", "simulate-sample-times"},
      {"/simulate", "simulate-perpetual-slip"},
      {"/stability", "stability-paper-orbit"},
      {"/continue", "continue-paper-ur-grazing"},
      {"/continue", "continue-start-not-an-orbit"}, /* a problem at run */
  };
  api_limits lim;
  api_limits_default(&lim);
  for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) {
    size_t len;
    char *body = case_request(CASES[i].name, &len);
    if (!body)
      continue;
    job_trace t = same_answer(CASES[i].name, endpoint(CASES[i].path), body, len,
                              &lim, JOB_FORWARD, 0);
    ASSERT_EQ_INT(t.opened, 1);
    ASSERT_EQ_INT(t.chunks, 1);
    ASSERT_EQ_INT(t.stages, 1);
    ASSERT_EQ_INT(t.items, 1);
    ASSERT_TRUE(t.content_type && !strcmp(t.content_type, "application/json"));
    free(body);
  }
  /* a chunk that does not exist is a problem, not a crash */
  api_job *j;
  api_response r;
  const char *body = "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,"
                     "\"ur\":0.6178,\"V\":1}}";
  ASSERT_EQ_INT(
      api_job_open(endpoint("/orbit"), body, strlen(body), &lim, &j, &r), 0);
  ASSERT_TRUE(api_job_visible(j, 0) && !api_job_visible(j, 1));
  ASSERT_EQ_INT(api_job_stage(j, 0), 0);
  ASSERT_EQ_INT(api_job_run(j, 1, NULL, &lim, NULL, &r), 500);
  ASSERT_TRUE(api_job_held(j) >= strlen(body) / 2);
  api_response_free(&r);
  api_job_free(j);
  api_job_free(NULL);
}

/* Append the item {"id": id, "path": path, "body": <case's request>} (or
 * the raw @a item when not NULL) to @a rq. */
static void add_item(json_t *rq, json_t *id, const char *path, const char *name,
                     const char *item) {
  json_t *it;
  if (item) {
    it = json_loads(item, JSON_DECODE_ANY, NULL);
  } else {
    size_t len;
    char *body = case_request(name, &len);
    it = json_object();
    json_object_set_new(it, "path", json_string(path));
    json_object_set_new(it, "body", json_loadb(body, len, 0, NULL));
    free(body);
  }
  if (id && json_is_object(it))
    json_object_set_new(it, "id", id);
  else
    json_decref(id);
  ASSERT_TRUE(it != NULL);
  json_array_append_new(rq, it);
}

/* A batch of @a n items of every path, good and bad (malloc'd). */
static char *mixed_batch(size_t n, size_t *len) {
  json_t *root = json_object(), *rq = json_array();
  json_object_set_new(root, "requests", rq);
  for (size_t i = 0; i < n; i++) {
    json_t *id = i % 3 == 0   ? json_integer((json_int_t)i)
                 : i % 3 == 1 ? json_sprintf("item \"%zu\"\n\u00e9", i)
                              : NULL;
    switch (i % 13) {
    case 0:
      add_item(rq, id, "/orbit", "orbit-paper-guess", NULL);
      break;
    case 1:
    case 6:
    case 9:
      add_item(rq, id, "/simulate", "simulate-final-only", NULL);
      break;
    case 2:
    case 7:
      add_item(rq, id, "/stability", "stability-paper-orbit", NULL);
      break;
    case 3: /* a problem of its body */
      add_item(rq, id, "/orbit", "orbit-chi-out-of-range", NULL);
      break;
    case 4: /* no such path */
      add_item(rq, id, NULL, NULL, "{\"path\":\"/nope\",\"body\":{}}");
      break;
    case 5: /* a path that does not compute */
      add_item(rq, id, NULL, NULL, "{\"path\":\"/health\",\"body\":{}}");
      break;
    case 8: /* not an object */
      add_item(rq, id, NULL, NULL, "5");
      break;
    case 10: /* no body */
      add_item(rq, id, NULL, NULL, "{\"path\":\"/simulate\"}");
      break;
    case 11: /* an NDJSON answer, carried as the array of its lines */
      add_item(rq, id, "/map", "map-axis-flat", NULL);
      break;
    default:
      add_item(rq, id, "/continue", "continue-start-not-an-orbit", NULL);
      break;
    }
  }
  char *text = json_dumps(root, JSON_COMPACT);
  *len = strlen(text);
  json_decref(root);
  return text;
}

/* EVIDENCE: stickslip_api.h "Jobs": a batch's body of the usual shape,
 * read an item at a time, is the batch the whole parse reads */
static void test_batch_shapes(void) {
  static const char *const BODIES[] = {
      "\n{ \"requests\" :\t[ {\"path\":\"/simulate\",\"body\":{\"params\":"
      "{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
      "\"initial\":[0,0,0,1],\"t_end\":3,\"fields\":[\"final\"]}} ,\r\n 5 ,"
      "\"x\", null, [1,{\"a\":\"]\\\"}\"}], "
      "{\"id\":\"\\u00e9\",\"path\":\"/nope\"}"
      " ]\r\n}\n",
      "{\"requests\":[{}],\"other\":1}",
      "\xef\xbb\xbf{\"requests\":[{}]}",
  };
  api_limits lim;
  api_limits_default(&lim);
  for (size_t i = 0; i < sizeof BODIES / sizeof BODIES[0]; i++)
    same_answer(BODIES[i], endpoint("/batch"), BODIES[i], strlen(BODIES[i]),
                &lim, JOB_FORWARD, 0);
  /* an item nested to the depth limit, and one level past it (refused) */
  for (int depth = lim.max_depth; depth <= lim.max_depth + 1; depth++) {
    char body[256];
    int k = snprintf(body, sizeof body, "{\"requests\":[");
    for (int d = 2; d < depth; d++)
      body[k++] = '[';
    for (int d = 2; d < depth; d++)
      body[k++] = ']';
    snprintf(body + k, sizeof body - (size_t)k, "]}");
    job_trace t = same_answer(body, endpoint("/batch"), body, strlen(body),
                              &lim, JOB_FORWARD, 0);
    ASSERT_EQ_INT(t.opened, depth <= lim.max_depth);
  }
}

/* EVIDENCE: stickslip_api.h "Jobs": a /batch is cut in groups of
 * consecutive items and a last chunk, and its answer is the synchronous
 * lines and done line, whatever order the chunks of a stage run in */
static void test_batch(void) {
  api_limits lim;
  api_limits_default(&lim);
  size_t ep = endpoint("/batch");
  static const size_t SIZES[] = {1, 31, 32, 33, 100};
  for (size_t s = 0; s < sizeof SIZES / sizeof SIZES[0]; s++) {
    size_t len, n = SIZES[s];
    char *body = mixed_batch(n, &len), what[64];
    snprintf(what, sizeof what, "a batch of %zu", n);
    for (int order = JOB_FORWARD; order <= JOB_SHUFFLE; order++) {
      job_trace t = same_answer(what, ep, body, len, &lim, (job_order)order,
                                (unsigned)(7 * n + 1));
      ASSERT_EQ_INT(t.chunks, (n + 31) / 32 + 1);
      ASSERT_EQ_INT(t.stages, 2);
      ASSERT_EQ_INT(t.items, n);
      ASSERT_TRUE(t.content_type &&
                  !strcmp(t.content_type, "application/x-ndjson"));
    }
    free(body);
  }
}

/* A store for the done line: chunk k's result is res[k]; fail: it cannot
 * be read. */
typedef struct fake_store {
  char **res;
  size_t *len;
  int fail;
} fake_store;

static int fake_read(void *cls, size_t k, char **buf, size_t *len) {
  fake_store *f = cls;
  if (f->fail)
    return -1;
  *buf = malloc(f->len[k] + 1);
  memcpy(*buf, f->res[k], f->len[k] + 1);
  *len = f->len[k];
  return 0;
}

/* EVIDENCE: stickslip_api.h "Jobs": the done line is made from the stored
 * results of the chunks before it (their statuses), and a result that
 * cannot be read is the store's problem, not a done line */
static void test_batch_done_reads(void) {
  api_limits lim;
  api_limits_default(&lim);
  size_t len, ep = endpoint("/batch");
  char *body = mixed_batch(40, &len);
  api_job *j;
  api_response r;
  ASSERT_EQ_INT(api_job_open(ep, body, len, &lim, &j, &r), 0);
  ASSERT_EQ_INT(api_job_chunks(j), 3);
  char *res[2];
  size_t lens[2];
  fake_store f = {res, lens, 0};
  api_job_inputs in = {fake_read, &f, 0};
  for (size_t k = 0; k < 2; k++) {
    ASSERT_EQ_INT(api_job_run(j, k, &in, &lim, NULL, &r), 200);
    res[k] = r.body;
    lens[k] = r.len;
  }
  ASSERT_EQ_INT(api_job_run(j, 2, &in, &lim, NULL, &r), 200);
  int ok = -1, failed = -1;
  json_t *done = json_loadb(r.body, r.len, 0, NULL);
  ok = (int)json_integer_value(json_object_get(done, "ok"));
  failed = (int)json_integer_value(json_object_get(done, "failed"));
  ASSERT_EQ_INT(ok + failed, 40);
  ASSERT_TRUE(json_real_value(json_object_get(done, "seconds")) == 0);
  json_decref(done);
  api_response_free(&r);
  /* one line's status changed in the store: the count follows it */
  char *at = strstr(res[1], "\"status\":200");
  ASSERT_TRUE(at != NULL);
  if (at)
    memcpy(at, "\"status\":422", 12);
  ASSERT_EQ_INT(api_job_run(j, 2, &in, &lim, NULL, &r), 200);
  done = json_loadb(r.body, r.len, 0, NULL);
  ASSERT_EQ_INT(json_integer_value(json_object_get(done, "ok")), ok - 1);
  ASSERT_EQ_INT(json_integer_value(json_object_get(done, "failed")),
                failed + 1);
  json_decref(done);
  api_response_free(&r);
  /* a started job reports the seconds since it started */
  in.started = (double)time(NULL) - 5;
  ASSERT_EQ_INT(api_job_run(j, 2, &in, &lim, NULL, &r), 200);
  done = json_loadb(r.body, r.len, 0, NULL);
  ASSERT_NEAR(json_real_value(json_object_get(done, "seconds")), 5.5, 1);
  json_decref(done);
  api_response_free(&r);
  in.started = 0;
  /* a result that is not the lines of its items */
  lens[1] -= 3;
  ASSERT_EQ_INT(api_job_run(j, 2, &in, &lim, NULL, &r), 500);
  api_response_free(&r);
  lens[1] += 3;
  /* nor is one whose status has more than three digits (read without
   * overflowing), or none */
  const char *bad_status[] = {"20000000000000", "2000", ""};
  for (size_t b = 0; b < sizeof bad_status / sizeof bad_status[0]; b++) {
    char *kept = res[1];
    size_t kept_len = lens[1], n = strlen(bad_status[b]);
    size_t at_st = (size_t)(strstr(kept, "\"status\":") - kept) + 9;
    char *t = malloc(kept_len + n + 1);
    ASSERT_TRUE(t != NULL);
    if (!t)
      break;
    memcpy(t, kept, at_st);
    memcpy(t + at_st, bad_status[b], n);
    memcpy(t + at_st + n, kept + at_st + 3, kept_len - at_st - 3);
    t[kept_len - 3 + n] = 0;
    res[1] = t;
    lens[1] = kept_len - 3 + n;
    ASSERT_EQ_INT(api_job_run(j, 2, &in, &lim, NULL, &r), 500);
    api_response_free(&r);
    res[1] = kept;
    lens[1] = kept_len;
    free(t);
  }
  /* a store that cannot be read */
  f.fail = 1;
  ASSERT_EQ_INT(api_job_run(j, 2, &in, &lim, NULL, &r), 503);
  ASSERT_TRUE(r.body && strstr(r.body, "/problems/store-unavailable"));
  api_response_free(&r);
  free(res[0]);
  free(res[1]);
  api_job_free(j);
  free(body);
}

static double mono(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The seconds api_job_open takes for a batch of @a n /orbit items (the
 * best of two runs), its body's bytes into *bytes. */
static double open_time(size_t n, size_t *bytes) {
  api_limits lim;
  api_limits_default(&lim);
  lim.max_batch_items = 1000000;
  static const char ITEM[] =
      "{\"id\":%zu,\"path\":\"/orbit\",\"body\":{\"params\":{\"chi\":0.2,"
      "\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},\"guess\":{"
      "\"durations\":[4.5,2.7,3.05]}}}";
  size_t cap = n * (sizeof ITEM + 8) + 32, len;
  char *body = malloc(cap);
  double best = 1e9;
  len = (size_t)snprintf(body, cap, "{\"requests\":[");
  for (size_t i = 0; i < n; i++) {
    if (i)
      body[len++] = ',';
    len += (size_t)snprintf(body + len, cap - len, ITEM, i);
  }
  len += (size_t)snprintf(body + len, cap - len, "]}");
  for (int run = 0; run < 2; run++) {
    api_job *j;
    api_response r;
    double t0 = mono();
    int rc = api_job_open(endpoint("/batch"), body, len, &lim, &j, &r);
    double dt = mono() - t0;
    best = dt < best ? dt : best;
    ASSERT_EQ_INT(rc, 0);
    if (rc == 0) {
      ASSERT_EQ_INT(api_job_chunks(j), n / 32 + (n % 32 != 0) + 1);
      ASSERT_EQ_INT(api_job_items(j), n);
      api_job_free(j);
    }
  }
  free(body);
  *bytes = len;
  return best;
}

/* EVIDENCE: docs/api/jobs.md: a sweep of a great many items is one request:
 * its job opens in a time proportional to its body.  100 000 items (13 MB)
 * open in about 0.5 s on a quiet machine; the check is on the growth (4
 * times the items in about 4 times the time, where a quadratic step would
 * take 16) and on a bound the shared machine keeps, not on a time */
static void test_batch_open_time(void) {
  size_t n = getenv("SS_JOB_ITEMS") ? (size_t)atol(getenv("SS_JOB_ITEMS"))
                                    : 100000,
         small, large;
  double ts = open_time(n / 4, &small), tl = open_time(n, &large);
  printf("a batch of %zu items (%.1f MB) opened as a job in %.3f s, of %zu "
         "in %.3f s: %.1f times the time for %.1f times the bytes\n",
         n, (double)large / 1e6, tl, n / 4, ts, tl / ts,
         (double)large / (double)small);
  ASSERT_TRUE(tl / ts < 8);
  /* under the sanitizers the same work takes several times longer */
  ASSERT_TRUE(tl < (getenv("SS_SLOW_BUILD") ? 20.0 : 3.0));
}

/* A server that cancelled the job. */
static int always(void *cls) {
  (void)cls;
  return 1;
}

/* EVIDENCE: stickslip_api.h "Jobs": srv->cancelled stops a chunk, whose
 * result then is no answer: never stored */
static void test_cancelled(void) {
  api_limits lim;
  api_limits_default(&lim);
  api_server_info srv;
  memset(&srv, 0, sizeof srv);
  srv.cancelled = always;
  size_t len;
  char *body = case_request("orbit-paper-guess", &len);
  api_job *j;
  api_response r;
  if (!body)
    return;
  ASSERT_EQ_INT(api_job_open(endpoint("/orbit"), body, len, &lim, &j, &r), 0);
  ASSERT_EQ_INT(api_job_run(j, 0, NULL, &lim, &srv, &r), 499);
  ASSERT_TRUE(r.body && strstr(r.body, "/problems/client-closed-request"));
  api_response_free(&r);
  api_job_free(j);
  free(body);
}

/* EVIDENCE: stickslip_api.h "Jobs": a chunk's result is the bytes to store,
 * also where the server streams large answers */
static void test_never_a_stream(void) {
  api_limits lim;
  api_limits_default(&lim);
  api_server_info srv;
  memset(&srv, 0, sizeof srv);
  srv.stream_above = 1; /* any answer with samples would stream */
  size_t len, ep = endpoint("/simulate");
  char *body = case_request("simulate-sample-times", &len);
  api_job *j;
  api_response r, s;
  if (!body)
    return;
  api_handle(ep, body, len, &lim, &srv, &s);
  ASSERT_TRUE(s.stream != NULL); /* synchronously, a stream */
  api_response_free(&s);
  api_handle(ep, body, len, &lim, NULL, &s);
  ASSERT_EQ_INT(api_job_open(ep, body, len, &lim, &j, &r), 0);
  ASSERT_EQ_INT(api_job_run(j, 0, NULL, &lim, &srv, &r), 200);
  ASSERT_TRUE(r.stream == NULL && r.body && r.len == s.len &&
              !memcmp(r.body, s.body, s.len));
  api_response_free(&r);
  api_response_free(&s);
  api_job_free(j);
  free(body);
}

/* EVIDENCE: stickslip_api.h "Jobs": a job is refused at submission with
 * the problem the synchronous request answers */
static void test_refused_at_open(void) {
  static const struct {
    const char *path, *body;
  } BAD[] = {
      {"/orbit", ""},
      {"/orbit", "{"},
      {"/orbit", "[]"},
      {"/orbit", "{\"params\":1}"},
      {"/orbit", "{\"nope\":1}"},
      {"/orbit", "{\"params\":{\"chi\":2,\"eta\":4,\"us\":0.07,\"ur\":0.6,"
                 "\"V\":1}}"},
      {"/orbit", "{\"a\":1,\"a\":2}"},
      {"/simulate", "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,"
                    "\"ur\":0.6178,\"V\":1}}"},
      {"/stability", "{}"},
      {"/continue", "{\"params\":{}}"},
      {"/batch", "{}"},
      {"/batch", "{\"requests\":[]}"},
      {"/batch", "{\"requests\":5}"},
      {"/batch", "{\"requests\":[{}],\"more\":1}"},
      {"/batch", "{\"requests\":[{},{},{},{}]}"}, /* over max_batch_items */
      /* the usual shape read an item at a time: what it must leave to the
       * whole parse */
      {"/batch", "{\"requests\":[{\"path\":\"/orbit\",\"body\":{}},]}"},
      {"/batch", "{\"requests\":[,{}]}"},
      {"/batch", "{\"requests\":[{\"path\":\"/orbit\",\"body\":{\"a\":}}]}"},
      {"/batch", "{\"requests\":[{\"id\":1,\"id\":2}]}"},
      {"/batch", "{\"requests\":[{\"path\":\"/orbit\"}]} x"},
      {"/batch", "{\"requests\":[{\"path\":\"/orbit\"}]"},
      {"/batch", "{\"requests\":[{\"path\":\"/orbit\"}"},
      {"/batch", "{\"requests\":[{\"path\":\"/orbit\"}],\"requests\":[]}"},
      {"/batch", "{\"requests\":[{\"path\":\"\\u00\"}]}"},
      {"/batch", "{\"requests\":[{\"path\":\"/orbit\"} {}]}"},
      {"/batch", "{\"requests\":[\"a]}"},
      {"/batch", "{\"requests\":[1e999]}"},
  };
  api_limits lim;
  api_limits_default(&lim);
  lim.max_batch_items = 3;
  for (size_t i = 0; i < sizeof BAD / sizeof BAD[0]; i++) {
    size_t ep = endpoint(BAD[i].path), len = strlen(BAD[i].body);
    api_response s, r;
    api_job *j = (api_job *)&j;
    api_handle(ep, BAD[i].body, len, &lim, NULL, &s);
    ASSERT_EQ_INT(api_job_open(ep, BAD[i].body, len, &lim, &j, &r), -1);
    ASSERT_TRUE(j == NULL);
    ASSERT_TRUE(s.status >= 400 && s.status < 500);
    test_checks_++;
    if (r.status != s.status || r.len != s.len ||
        memcmp(r.body, s.body, s.len) ||
        strcmp(r.content_type, "application/problem+json"))
      TEST_FAIL_("%s %s: at submission %d %s, synchronously %d %s", BAD[i].path,
                 BAD[i].body, r.status, r.body, s.status, s.body);
    api_response_free(&s);
    api_response_free(&r);
  }
  /* only a computing endpoint runs as a job */
  size_t health = api_endpoint_count();
  api_job *j;
  api_response r;
  ASSERT_EQ_INT(api_route("GET", "/health", &health), 200);
  ASSERT_EQ_INT(api_job_open(health, "{}", 2, &lim, &j, &r), -1);
  ASSERT_EQ_INT(r.status, 404);
  api_response_free(&r);
  ASSERT_EQ_INT(api_job_open(api_endpoint_count(), "{}", 2, &lim, &j, &r), -1);
  api_response_free(&r);
}

/* The string at @a key of @a o, or "". */
static const char *str(const json_t *o, const char *key) {
  const char *s = json_string_value(json_object_get(o, key));
  return s ? s : "";
}

static json_t *parsed(const api_response *r) {
  json_t *j = r->body ? json_loadb(r->body, r->len, 0, NULL) : NULL;
  ASSERT_EQ_INT(r->status, 200);
  ASSERT_TRUE(r->content_type && !strcmp(r->content_type, "application/json"));
  ASSERT_TRUE(json_is_object(j));
  return j;
}

/* The link of @a rel in @a links, or NULL. */
static const json_t *link_of(const json_t *links, const char *rel) {
  size_t i;
  const json_t *l;
  json_array_foreach(links, i, l) if (!strcmp(str(l, "rel"), rel)) return l;
  return NULL;
}

static json_t *status_doc(const api_job_info *in) {
  api_response r;
  api_job_status_json(in, &r);
  json_t *j = parsed(&r);
  api_response_free(&r);
  return j;
}

static long progress_of(const api_job_info *in) {
  json_t *j = status_doc(in);
  long p = (long)json_integer_value(json_object_get(j, "progress"));
  ASSERT_TRUE(json_is_integer(json_object_get(j, "progress")));
  json_decref(j);
  return p;
}

/* EVIDENCE: docs/api/jobs.md / OGC API - Processes statusInfo: the status
 * document's fields, its times in RFC 3339 UTC, its links */
static void test_status(void) {
  static const char ID[] = "0123456789abcdef0123456789abcdef";
  api_job_info in = {
      ID, "/orbit", "running", 1764193445.1239, 1764193446.5, 0, 0, 10, 5,
      2,  1,        NULL};
  json_t *j = status_doc(&in);
  ASSERT_TRUE(!strcmp(str(j, "id"), ID));
  ASSERT_TRUE(!strcmp(str(j, "jobID"), ID));
  ASSERT_TRUE(!strcmp(str(j, "type"), "process"));
  ASSERT_TRUE(!strcmp(str(j, "processID"), "orbit"));
  ASSERT_TRUE(!strcmp(str(j, "path"), "/orbit"));
  ASSERT_TRUE(!strcmp(str(j, "status"), "running"));
  ASSERT_TRUE(!strcmp(str(j, "message"), "5 of 10 items done"));
  ASSERT_EQ_INT(json_integer_value(json_object_get(j, "progress")), 50);
  ASSERT_TRUE(!strcmp(str(j, "created"), "2025-11-26T21:44:05.123Z"));
  ASSERT_TRUE(!strcmp(str(j, "started"), "2025-11-26T21:44:06.500Z"));
  ASSERT_TRUE(!json_object_get(j, "updated")); /* not yet: absent */
  ASSERT_TRUE(!json_object_get(j, "finished"));
  json_t *items = json_object_get(j, "items");
  ASSERT_EQ_INT(json_integer_value(json_object_get(items, "done")), 5);
  ASSERT_EQ_INT(json_integer_value(json_object_get(items, "total")), 10);
  const json_t *links = json_object_get(j, "links");
  const json_t *self = link_of(links, "self");
  const json_t *res =
      link_of(links, "http://www.opengis.net/def/rel/ogc/1.0/results");
  ASSERT_TRUE(self && !strcmp(str(self, "href"),
                              "/jobs/0123456789abcdef0123456789abcdef"));
  ASSERT_TRUE(res && !strcmp(str(res, "href"),
                             "/jobs/0123456789abcdef0123456789abcdef/results"));
  json_decref(j);

  /* the message the server gives, and the time it finished */
  in.status = "failed";
  in.message = "the chunk 3 failed";
  in.updated = in.finished = 1764193500.0;
  j = status_doc(&in);
  ASSERT_TRUE(!strcmp(str(j, "message"), "the chunk 3 failed"));
  ASSERT_TRUE(!strcmp(str(j, "finished"), "2025-11-26T21:45:00.000Z"));
  ASSERT_TRUE(!strcmp(str(j, "updated"), "2025-11-26T21:45:00.000Z"));
  json_decref(j);

  /* progress: from items, 100 only once successful, monotone */
  in.status = "running";
  in.message = NULL;
  long last = -1;
  for (long d = 0; d <= 10; d++) {
    in.items_done = d;
    long p = progress_of(&in);
    ASSERT_TRUE(p >= last && p <= 99);
    last = p;
  }
  ASSERT_EQ_INT(last, 99); /* every item done, a chunk to come */
  in.status = "successful";
  in.chunks_done = in.chunks;
  ASSERT_EQ_INT(progress_of(&in), 100);
  in.status = "accepted";
  in.items_done = 0;
  in.chunks_done = 0;
  ASSERT_EQ_INT(progress_of(&in), 0);
  in.items = 0; /* no items: the chunks count */
  in.chunks_done = 1;
  ASSERT_EQ_INT(progress_of(&in), 50);
}

/* EVIDENCE: docs/api/jobs.md: GET /jobs, newest first, paged */
static void test_list(void) {
  api_job_info jobs[3];
  static const char *const IDS[] = {"0000000000000000000000000000000a",
                                    "0000000000000000000000000000000b",
                                    "0000000000000000000000000000000c"};
  for (int i = 0; i < 3; i++)
    jobs[i] = (api_job_info){IDS[i], "/batch", "accepted", 1764193445.0 - i,
                             0,      0,        0,          100,
                             0,      5,        0,          NULL};
  api_response r;
  api_job_list_json(jobs, 3, 3, 3, 10, &r);
  json_t *j = parsed(&r);
  api_response_free(&r);
  json_t *list = json_object_get(j, "jobs");
  ASSERT_EQ_INT(json_array_size(list), 3);
  ASSERT_EQ_INT(json_integer_value(json_object_get(j, "total")), 10);
  for (size_t i = 0; i < 3; i++)
    ASSERT_TRUE(!strcmp(str(json_array_get(list, i), "id"), IDS[i]));
  const json_t *links = json_object_get(j, "links");
  ASSERT_TRUE(
      !strcmp(str(link_of(links, "self"), "href"), "/jobs?offset=3&limit=3"));
  ASSERT_TRUE(
      !strcmp(str(link_of(links, "next"), "href"), "/jobs?offset=6&limit=3"));
  ASSERT_TRUE(
      !strcmp(str(link_of(links, "prev"), "href"), "/jobs?offset=0&limit=3"));
  json_decref(j);
  /* the first page has no previous one, the last no next one */
  api_job_list_json(jobs, 2, 0, 2, 2, &r);
  j = parsed(&r);
  api_response_free(&r);
  links = json_object_get(j, "links");
  ASSERT_TRUE(link_of(links, "self") && !link_of(links, "next") &&
              !link_of(links, "prev"));
  json_decref(j);
  api_job_list_json(NULL, 0, 0, 10, 0, &r);
  j = parsed(&r);
  api_response_free(&r);
  ASSERT_EQ_INT(json_array_size(json_object_get(j, "jobs")), 0);
  json_decref(j);
}

int main(int argc, char **argv) {
  if (argc < 2)
    return 2;
  cases_dir = argv[1];
  ss_gsl_quiet();
  test_single_answers();
  test_cancelled();
  test_never_a_stream();
  test_refused_at_open();
  test_batch();
  test_batch_shapes();
  test_batch_done_reads();
  test_batch_open_time();
  test_status();
  test_list();
  TEST_DONE();
}
