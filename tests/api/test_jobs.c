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

/* EVIDENCE: README "Jobs" / OGC API - Processes statusInfo: the status
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

/* EVIDENCE: README "Jobs": GET /jobs, newest first, paged */
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
  test_status();
  test_list();
  TEST_DONE();
}
