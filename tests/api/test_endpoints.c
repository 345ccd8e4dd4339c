/*
 * test_endpoints.c: the endpoint table against the OpenAPI document and the
 * codec cases.  Every row of the table is a path and method of
 * api/openapi.json and every path and method there is a row; labels are
 * unique; routing finds each row, refuses another method with 405 and an
 * unknown path with 404; every computing endpoint has codec cases; every
 * problem type has its page, and so has every "/problems/..." the sources
 * write.
 * Usage: test_endpoints CASES_DIR SOURCE_DIR
 */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <dirent.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "problem.h"
#include "stickslip_api.h"
#include "test.h"

/* EVIDENCE: docs/develop.md: the endpoint table is the only list of
 * endpoints, and the OpenAPI document agrees with it */
static void test_spec_and_table(void) {
  json_t *spec = json_loads(api_openapi_json(), 0, NULL);
  json_t *paths = json_object_get(spec, "paths");
  size_t n = api_endpoint_count(), in_spec = 0, served = 0;
  ASSERT_TRUE(json_is_object(paths));
  ASSERT_TRUE(n >= 7);
  for (size_t i = 0; i < n; i++) {
    const api_endpoint *row = api_endpoint_at(i);
    char method[8];
    size_t k = 0;
    for (; row->method[k] && k + 1 < sizeof method; k++)
      method[k] = (char)tolower((unsigned char)row->method[k]);
    method[k] = 0;
    json_t *item = json_object_get(paths, row->path);
    if (!json_object_get(item, method))
      TEST_FAIL_("%s %s is in the table but not in openapi.json", row->method,
                 row->path);
    for (size_t j = 0; j < i; j++)
      if (!strcmp(api_endpoint_at(j)->label, row->label) ||
          !strcmp(api_endpoint_at(j)->path, row->path))
        TEST_FAIL_("rows %zu and %zu share a label or a path", j, i);
    size_t got = n;
    ASSERT_EQ_INT(api_route(row->method, row->path, &got), 200);
    ASSERT_TRUE(got == i);
    ASSERT_EQ_INT(api_route("DELETE", row->path, &got), 405);
    ASSERT_TRUE(got == i);
    /* an inline endpoint takes no body: GET, and HEAD as GET */
    if (row->run_class == API_RUN_INLINE) {
      ASSERT_TRUE(!strcmp(row->method, "GET"));
      ASSERT_EQ_INT(api_route("HEAD", row->path, &got), 200);
    } else {
      ASSERT_TRUE(!strcmp(row->method, "POST"));
    }
  }
  const char *path;
  json_t *item;
  json_object_foreach(paths, path, item) {
    const char *m;
    json_t *op;
    /* the server's own resources (/jobs...) say so; none is a row */
    const char *by =
        json_string_value(json_object_get(item, "x-stickslip-served-by"));
    if (by && strcmp(by, "server"))
      TEST_FAIL_("%s is served by \"%s\", which is not the server", path, by);
    json_object_foreach(item, m, op) {
      char method[8];
      size_t k = 0, got;
      if (!strcmp(m, "parameters") || !strcmp(m, "summary") ||
          !strcmp(m, "description") || !strncmp(m, "x-", 2))
        continue; /* not an operation */
      for (; m[k] && k + 1 < sizeof method; k++)
        method[k] = (char)toupper((unsigned char)m[k]);
      method[k] = 0;
      int route = api_route(method, path, &got);
      if (by && route != 404)
        TEST_FAIL_("%s %s is the server's in openapi.json but a path of the "
                   "table",
                   method, path);
      else if (!by && route != 200)
        TEST_FAIL_("%s %s is in openapi.json but not in the table", method,
                   path);
      in_spec += !by;
      served += by != NULL;
    }
  }
  /* the jobs' resources (README "Jobs") and the problem types' pages */
  ASSERT_EQ_INT(served, 5);
  ASSERT_TRUE(in_spec == n);
  size_t got;
  ASSERT_EQ_INT(api_route("GET", "/nope", &got), 404);
  ASSERT_EQ_INT(api_route("GET", "//orbit", &got), 404);
  ASSERT_TRUE(api_endpoint_at(n) == NULL);
  json_decref(spec);
}

/* EVIDENCE: docs/develop.md: each computing endpoint has codec cases */
static void test_cases_cover_table(const char *dir) {
  for (size_t i = 0; i < api_endpoint_count(); i++) {
    const api_endpoint *row = api_endpoint_at(i);
    if (row->run_class != API_RUN_COMPUTE)
      continue;
    DIR *d = opendir(dir);
    struct dirent *de;
    int cases = 0;
    size_t l = strlen(row->label);
    while (d && (de = readdir(d)))
      cases += !strncmp(de->d_name, row->label, l) && de->d_name[l] == '-';
    if (d)
      closedir(d);
    if (cases < 3)
      TEST_FAIL_("%s has %d codec cases in %s, want at least 3", row->path,
                 cases, dir);
    test_checks_++;
  }
}

/* EVIDENCE: docs/api/errors.md: every problem type has one HTTP status, and
 * the OpenAPI document lists exactly the types the table has */
static void test_problem_table(void) {
  json_t *spec = json_loads(api_openapi_json(), 0, NULL);
  json_t *types = json_object_get(
      json_object_get(
          json_object_get(
              json_object_get(
                  json_object_get(json_object_get(spec, "components"),
                                  "schemas"),
                  "Problem"),
              "properties"),
          "type"),
      "enum");
  size_t listed = 0;
  for (int k = 0; k < API_P_COUNT; k++) {
    api_response r;
    api_problem(&r, (api_problem_kind)k, "x", NULL, NULL, 0);
    json_t *body = json_loads(r.body, 0, NULL);
    const char *type = json_string_value(json_object_get(body, "type"));
    int found = 0;
    for (size_t i = 0; type && i < json_array_size(types); i++)
      found |= !strcmp(type, json_string_value(json_array_get(types, i)));
    if (!found)
      TEST_FAIL_("problem type %s is not in openapi.json", type ? type : "?");
    test_checks_++;
    ASSERT_EQ_INT(r.status, api_problem_status((api_problem_kind)k));
    json_decref(body);
    api_response_free(&r);
  }
  /* two kinds share "limit-exceeded" (413 for the body, 422 otherwise) */
  listed = json_array_size(types);
  ASSERT_TRUE(listed + 1 == (size_t)API_P_COUNT);
  json_decref(spec);

  ASSERT_EQ_INT(api_problem_status(API_P_INVALID_JSON), 400);
  ASSERT_EQ_INT(api_problem_status(API_P_LIMIT), 422);
  ASSERT_EQ_INT(api_problem_status(API_P_OUT_OF_MEMORY), 503);
  ASSERT_EQ_INT(api_problem_status(API_P_COUNT), 500);
  api_response r;
  api_problem(&r, API_P_METHOD_NOT_ALLOWED, "GET only", NULL, NULL, 0);
  ASSERT_EQ_INT(r.status, 405);
  ASSERT_TRUE(strstr(r.body, "\"type\":\"/problems/method-not-allowed\""));
  ASSERT_TRUE(!strcmp(r.content_type, "application/problem+json"));
  api_response_free(&r);
}

/* The page of problem type @a type as JSON: 0 when it is one, whose
 * statuses include @a status (0: any). */
static int page_ok(const char *type, int status) {
  api_response r;
  char uri[96];
  int ok = api_problem_page(type, 0, &r) == 200 &&
           !strcmp(r.content_type, "application/json");
  json_t *body = ok ? json_loads(r.body, 0, NULL) : NULL;
  json_t *st = json_object_get(body, "status");
  snprintf(uri, sizeof uri, "/problems/%s", type);
  ok = ok && !strcmp(json_string_value(json_object_get(body, "type")), uri) &&
       json_string_length(json_object_get(body, "meaning")) > 40 &&
       json_string_length(json_object_get(body, "fix")) > 20;
  int has = status == 0;
  for (size_t i = 0; ok && i < json_array_size(st); i++)
    has |= json_integer_value(json_array_get(st, i)) == status;
  json_decref(body);
  api_response_free(&r);
  return ok && has ? 0 : -1;
}

/* Every "/problems/<type>" written in the files under @a path (a file or a
 * directory, recursively: C, Python, JSON) must have a page; the count of
 * those met into *n. */
static void scan_sources(const char *path, size_t *n) {
  DIR *d = opendir(path);
  if (d) {
    struct dirent *de;
    while ((de = readdir(d))) {
      char sub[1024];
      if (de->d_name[0] == '.')
        continue;
      snprintf(sub, sizeof sub, "%s/%s", path, de->d_name);
      scan_sources(sub, n);
    }
    closedir(d);
    return;
  }
  const char *ext = strrchr(path, '.');
  if (!ext || (strcmp(ext, ".c") && strcmp(ext, ".h") && strcmp(ext, ".py") &&
               strcmp(ext, ".json")))
    return;
  FILE *f = fopen(path, "rb");
  char *text = NULL;
  size_t cap = 0;
  ssize_t len = f ? getdelim(&text, &cap, '\0', f) : -1;
  for (char *p = len > 0 ? strstr(text, "/problems/") : NULL; p;
       p = strstr(p + 1, "/problems/")) {
    char type[64];
    size_t k = 0;
    for (const char *q = p + 10;
         (islower((unsigned char)*q) || *q == '-') && k + 1 < sizeof type; q++)
      type[k++] = *q;
    type[k] = 0;
    if (!k || (p[10 + k] == '{')) /* "/problems/{type}", a template */
      continue;
    (*n)++;
    if (page_ok(type, 0))
      TEST_FAIL_("%s names /problems/%s, which has no page", path, type);
  }
  free(text);
  if (f)
    fclose(f);
}

/* EVIDENCE: RFC 9457 section 3.1.1, a type URI that documents itself:
 * every problem type the daemon answers (the table's, and every one its
 * sources, tests and contract write) has a page, HTML or JSON; the
 * contract's list of pages is the table's; another type is 404 */
static void test_problem_pages(const char *root) {
  for (int k = 0; k < API_P_COUNT; k++) {
    const char *type = api_problem_type((api_problem_kind)k);
    if (page_ok(type, api_problem_status((api_problem_kind)k)))
      TEST_FAIL_("problem type %s (HTTP %d) has no page", type,
                 api_problem_status((api_problem_kind)k));
    test_checks_++;
    api_response r;
    ASSERT_EQ_INT(api_problem_page(type, 1, &r), 200);
    ASSERT_TRUE(!strncmp(r.content_type, "text/html", 9) &&
                !strncmp(r.body, "<!DOCTYPE html>", 15) &&
                strstr(r.body, "How to fix the request"));
    api_response_free(&r);
  }
  json_t *spec = json_loads(api_openapi_json(), 0, NULL);
  json_t *types = json_object_get(
      json_object_get(
          json_object_get(json_object_get(json_object_get(spec, "components"),
                                          "parameters"),
                          "ProblemType"),
          "schema"),
      "enum");
  size_t pages = api_problem_page_count();
  ASSERT_TRUE(json_array_size(types) == pages);
  for (size_t i = 0; i < pages; i++) {
    /* a page only for a type of the table */
    int of_table = 0;
    for (int k = 0; k < API_P_COUNT; k++)
      of_table |= !strcmp(api_problem_page_type(i),
                          api_problem_type((api_problem_kind)k));
    if (!of_table)
      TEST_FAIL_("page %s is of no problem type", api_problem_page_type(i));
    if (strcmp(json_string_value(json_array_get(types, i)),
               api_problem_page_type(i)))
      TEST_FAIL_("openapi.json's ProblemType %zu is not page %s", i,
                 api_problem_page_type(i));
    test_checks_++;
  }
  json_decref(spec);
  api_response r;
  ASSERT_EQ_INT(api_problem_page("no-such-type", 0, &r), 404);
  ASSERT_TRUE(strstr(r.body, "\"type\":\"/problems/not-found\""));
  api_response_free(&r);
  ASSERT_EQ_INT(api_problem_page("", 1, &r), 404);
  api_response_free(&r);
  /* the types written in the sources, the tests and the contract */
  static const char *const where[] = {
      "api/src",    "api/include", "server",          "python",
      "tests/http", "tests/api",   "api/openapi.json"};
  size_t met = 0;
  for (size_t i = 0; i < sizeof where / sizeof where[0]; i++) {
    char path[512];
    snprintf(path, sizeof path, "%s/%s", root, where[i]);
    scan_sources(path, &met);
  }
  /* the tests alone name a dozen types */
  if (met < 50)
    TEST_FAIL_("only %zu \"/problems/\" met under %s", met, root);
}

/* The answer the status table gives a core status. */
static int http_of(int status) {
  api_err e;
  api_response r;
  memset(&e, 0, sizeof e);
  api__status(&e, status, "/x", "detail");
  api__problem_response(&e, &r);
  int st = r.status;
  api_response_free(&r);
  return st;
}

/* EVIDENCE: docs/api/errors.md: a failure of the core leaves as one row of the
 * table whatever endpoint met it; a status missing from it is internal */
static void test_status_table(void) {
  ASSERT_EQ_INT(http_of(SS_EDOMAIN), 422);
  ASSERT_EQ_INT(http_of(SS_EINVAL), 422);
  ASSERT_EQ_INT(http_of(SS_ESINGULAR), 422);
  ASSERT_EQ_INT(http_of(SS_ENOCONV), 422);
  ASSERT_EQ_INT(http_of(SS_ELIMIT_EVENTS), 422);
  ASSERT_EQ_INT(http_of(SS_ELIMIT_SAMPLES), 422);
  ASSERT_EQ_INT(http_of(SS_ELIMIT_TIME), 422);
  ASSERT_EQ_INT(http_of(SS_ENOMEM), 503);
  ASSERT_EQ_INT(http_of(SS_EBUG), 500);
  /* not a failure, and not in the table: never guessed */
  ASSERT_EQ_INT(http_of(SS_INFEASIBLE), 500);
  ASSERT_EQ_INT(http_of(-1000), 500);
  api_err e;
  memset(&e, 0, sizeof e);
  api__status_limit(&e, SS_ELIMIT_TIME, "max_seconds", 2, "/t_end", "slow");
  ASSERT_TRUE(e.kind == API_P_LIMIT && !strcmp(e.limit, "max_seconds"));
  ASSERT_TRUE(!strcmp(e.pointer, "/t_end"));
}

/* The answer of @a body at @a ep read from a stream in pieces of @a step
 * bytes (malloc'd), or NULL when it was not streamed. */
static char *streamed(size_t ep, const char *body, size_t step, size_t *n) {
  api_limits lim;
  api_server_info srv = {0};
  api_response r;
  api_limits_default(&lim);
  srv.stream_above = 1;
  api_handle(ep, body, strlen(body), &lim, &srv, &r);
  if (!r.stream || r.body) {
    api_response_free(&r);
    return NULL;
  }
  size_t cap = 1 << 16, len = 0;
  char *out = malloc(cap);
  long k;
  do {
    if (len + step + 1 > cap)
      out = realloc(out, cap = 2 * (len + step + 1));
    k = api_stream_read(r.stream, out + len, step);
    ASSERT_TRUE(k >= 0 && (size_t)k <= step);
    len += (size_t)(k > 0 ? k : 0);
  } while (k > 0);
  out[len] = 0;
  *n = len;
  api_response_free(&r);
  return out;
}

/* EVIDENCE: docs/howto/limits.md: a streamed answer is the same bytes as the
 * answer written whole, however it is read */
static void test_streams(void) {
  static const char *const bodies[][2] = {
      {"/simulate",
       "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
       "\"V\":1},\"initial\":[1.27,4.36,-0.8,1.0],\"t_end\":300,"
       "\"samples\":{\"n\":777}}"},
      {"/simulate",
       "{\"physical\":{\"m1\":2.5,\"m2\":0.625,\"k1\":8,\"k2\":2,"
       "\"Fs\":0.724,\"Fr\":6.178,\"v0\":2},\"initial\":[0,0,0,2],"
       "\"t_end\":50,\"samples\":{\"t\":[0,1,2.5]},\"events\":true}"},
      {"/orbit", "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,"
                 "\"ur\":0.6178,\"V\":1},\"kind\":\"all\",\"samples\":50}"},
  };
  static const size_t steps[] = {1, 7, 100, 4096, 1 << 20};
  int compared = 0;
  for (size_t b = 0; b < sizeof bodies / sizeof bodies[0]; b++) {
    size_t ep;
    ASSERT_EQ_INT(api_route("POST", bodies[b][0], &ep), 200);
    api_limits lim;
    api_response whole;
    api_limits_default(&lim);
    api_handle(ep, bodies[b][1], strlen(bodies[b][1]), &lim, NULL, &whole);
    if (whole.status != 200)
      printf("%s: %s\n", bodies[b][0], whole.body);
    ASSERT_EQ_INT(whole.status, 200);
    ASSERT_TRUE(whole.body && !whole.stream);
    for (size_t s = 0; s < sizeof steps / sizeof steps[0]; s++) {
      size_t n = 0;
      char *t = streamed(ep, bodies[b][1], steps[s], &n);
      ASSERT_TRUE(t != NULL);
      if (t) {
        ASSERT_EQ_INT((int)n, (int)whole.len);
        ASSERT_TRUE(n == whole.len && memcmp(t, whole.body, n) == 0);
        compared++;
      }
      free(t);
    }
    api_response_free(&whole);
  }
  ASSERT_EQ_INT(compared, 15);
}

/* The text of stream @a s read in pieces of @a step bytes (malloc'd); the
 * stream is freed. */
static char *read_all(api_stream *s, size_t step) {
  size_t cap = 256, len = 0;
  char *out = malloc(cap);
  long k;
  do {
    if (len + step + 1 > cap)
      out = realloc(out, cap = 2 * (len + step + 1));
    k = api_stream_read(s, out + len, step);
    ASSERT_TRUE(k >= 0 && (size_t)k <= step);
    len += (size_t)(k > 0 ? k : 0);
  } while (k > 0);
  out[len] = 0;
  api_stream_free(s);
  return out;
}

/* EVIDENCE: docs/api/batch.md: an item's line carries the answer its body
 * gets when posted alone; a bad item gets its own line, with a pointer into
 * the item, and the others go on; the last line counts them */
/* A batch's body is checked in its text, item by item, where it can be:
 * whatever that check lets through must be what jansson reads, so that a
 * body jansson refuses gets the whole parse's problem (its line and column),
 * and the items' lines are those of the whole parse's items. */
static void test_batch_text(void) {
  static const char *const bad[] = {
      "{\"a\":1,\"a\":2}",             /* a key twice */
      "{\"p\":{\"c\":1,\"c\":1}}",     /* a key twice, deeper */
      "{\"a\":1e400}",                 /* a real over a double */
      "{\"a\":123456789012345678901}", /* an integer over 64 bits */
      "{\"a\":\"\\u0000\"}",           /* NUL */
      "{\"a\":\"\\ud800\"}",           /* a lone surrogate */
      "{\"a\":\"x\x01\"}",             /* a control character */
      "{\"a\":\"\xff\"}",              /* not UTF-8 */
      "{\"a\":01}",                    /* a leading zero */
      "{\"a\":1,}",                    /* a comma before the brace */
      "{\"a\":-}",
      "{\"a\":tru}",
  };
  api_limits lim;
  api_limits_default(&lim);
  size_t ep;
  ASSERT_EQ_INT(api_route("POST", "/batch", &ep), 200);
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
    char body[256];
    snprintf(body, sizeof body,
             "{\"requests\":[{\"id\":1,\"path\":\"/stability\",\"body\":%s}]}",
             bad[i]);
    api_batch *b = NULL;
    api_response open, whole;
    int rc = api_batch_open(body, strlen(body), &lim, &b, &open);
    api_handle(ep, body, strlen(body), &lim, NULL, &whole);
    ASSERT_EQ_INT(rc, -1);
    ASSERT_EQ_INT(open.status, 400);
    ASSERT_EQ_INT(whole.status, 400);
    ASSERT_TRUE(open.body && whole.body && !strcmp(open.body, whole.body));
    api_batch_free(b);
    api_response_free(&open);
    api_response_free(&whole);
  }
}

static void test_batch(void) {
  static const char *const orbit =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"kind\":\"all\"}";
  static const char *const bad_chi =
      "{\"params\":{\"chi\":-1,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1}}";
  char body[1024];
  snprintf(body, sizeof body,
           "{\"requests\":[{\"id\":\"a\",\"path\":\"/orbit\",\"body\":%s},"
           "{\"id\":2,\"path\":\"/orbit\",\"body\":%s},"
           "{\"path\":\"/health\",\"body\":{}},"
           "{\"id\":3,\"path\":\"/orbit\",\"body\":{},\"x\":1}]}",
           orbit, bad_chi);
  api_limits lim;
  api_limits_default(&lim);
  size_t ep, orbit_ep;
  ASSERT_EQ_INT(api_route("POST", "/batch", &ep), 200);
  ASSERT_EQ_INT(api_route("POST", "/orbit", &orbit_ep), 200);

  /* the answer to each item alone, as its line should carry it */
  api_response alone[2];
  api_handle(orbit_ep, orbit, strlen(orbit), &lim, NULL, &alone[0]);
  api_handle(orbit_ep, bad_chi, strlen(bad_chi), &lim, NULL, &alone[1]);
  ASSERT_EQ_INT(alone[0].status, 200);
  ASSERT_EQ_INT(alone[1].status, 422);

  /* the whole answer, served in order */
  api_response whole;
  api_handle(ep, body, strlen(body), &lim, NULL, &whole);
  ASSERT_EQ_INT(whole.status, 200);
  ASSERT_TRUE(whole.content_type &&
              !strcmp(whole.content_type, "application/x-ndjson"));
  json_t *lines[5] = {NULL};
  size_t nl = 0;
  for (char *p = whole.body, *e; p && *p && nl < 5; p = e + 1) {
    if (!(e = strchr(p, '\n')))
      break;
    lines[nl++] = json_loadb(p, (size_t)(e - p), 0, NULL);
  }
  ASSERT_EQ_INT((int)nl, 5);
  static const struct {
    int status;
    const char *pointer;
  } want[4] = {
      {200, NULL}, {422, "/body/params/chi"}, {422, "/path"}, {422, "/x"}};
  for (size_t i = 0; i < 4 && i < nl; i++) {
    json_t *l = lines[i];
    ASSERT_TRUE(json_integer_value(json_object_get(l, "index")) == (int)i);
    ASSERT_EQ_INT((int)json_integer_value(json_object_get(l, "status")),
                  want[i].status);
    if (want[i].pointer) {
      const char *ptr = json_string_value(
          json_object_get(json_object_get(l, "body"), "pointer"));
      ASSERT_TRUE(ptr && !strcmp(ptr, want[i].pointer));
    }
  }
  ASSERT_TRUE(!strcmp(json_string_value(json_object_get(lines[0], "id")), "a"));
  ASSERT_TRUE(json_integer_value(json_object_get(lines[1], "id")) == 2);
  ASSERT_TRUE(json_is_null(json_object_get(lines[2], "id")));
  /* the item's body is the answer alone, but for the pointer's prefix */
  json_t *a0 = json_loads(alone[0].body, 0, NULL);
  ASSERT_TRUE(json_equal(a0, json_object_get(lines[0], "body")));
  json_decref(a0);
  json_t *a1 = json_loads(alone[1].body, 0, NULL);
  json_object_set_new(a1, "pointer", json_string("/body/params/chi"));
  ASSERT_TRUE(json_equal(a1, json_object_get(lines[1], "body")));
  json_decref(a1);
  ASSERT_TRUE(json_is_true(json_object_get(lines[4], "done")));
  ASSERT_TRUE(json_integer_value(json_object_get(lines[4], "ok")) == 1);
  ASSERT_TRUE(json_integer_value(json_object_get(lines[4], "failed")) == 3);
  for (size_t i = 0; i < nl; i++)
    json_decref(lines[i]);
  api_response_free(&whole);

  /* item by item, as the server runs them: each line is one line of JSON,
   * however it is read, and the batch keeps its body's text and a few words
   * an item, no tree */
  api_batch *b;
  api_response out;
  ASSERT_EQ_INT(api_batch_open(body, strlen(body), &lim, &b, &out), 0);
  ASSERT_TRUE(b && api_batch_size(b) == 4);
  ASSERT_TRUE(api_batch_held(b) > strlen(orbit) + strlen(bad_chi) &&
              api_batch_held(b) < strlen(body) + 4 * 64);
  for (size_t step = 1; b && step <= 4096; step *= 64) {
    api_response r;
    size_t held = 0;
    ASSERT_EQ_INT(api_batch_run(b, 0, &lim, NULL, &r), 200);
    char *t = read_all(api_batch_line(b, 0, &r, &held), step);
    ASSERT_TRUE(held >= strlen(t));
    size_t n = strlen(t);
    ASSERT_TRUE(n > 1 && t[n - 1] == '\n' && !memchr(t, '\n', n - 1));
    json_t *l = json_loads(t, 0, NULL);
    json_t *a = json_loads(alone[0].body, 0, NULL);
    ASSERT_TRUE(json_equal(a, json_object_get(l, "body")));
    json_decref(a);
    json_decref(l);
    free(t);
  }
  api_batch_free(b);
  api_response_free(&alone[0]);
  api_response_free(&alone[1]);

  /* refused as a whole, with the pointer into the batch */
  static const struct {
    const char *body, *pointer;
    int status;
  } whole_bad[] = {{"{\"requests\":[]}", "/requests", 422},
                   {"{\"requests\":{}}", "/requests", 422},
                   {"{}", "/requests", 422},
                   {"{\"requests\":[1],\"more\":[]}", "/more", 422},
                   {"{\"requests\":[1,2,3]}", "/requests", 422}};
  lim.max_batch_items = 2;
  for (size_t i = 0; i < sizeof whole_bad / sizeof whole_bad[0]; i++) {
    const char *bb = whole_bad[i].body;
    ASSERT_EQ_INT(api_batch_open(bb, strlen(bb), &lim, &b, &out), -1);
    ASSERT_TRUE(b == NULL);
    json_t *p = json_loads(out.body, 0, NULL);
    const char *ptr = json_string_value(json_object_get(p, "pointer"));
    if (!ptr || strcmp(ptr, whole_bad[i].pointer) ||
        out.status != whole_bad[i].status)
      TEST_FAIL_("batch %s: %d %s", bb, out.status, out.body);
    test_checks_++;
    json_decref(p);
    api_response_free(&out);
  }
}

/* EVIDENCE: docs/api/continue.md: "fields" chooses the per-point fields
 * (value always comes); a client that asks for the parameter and the
 * period gets nothing else per point */
static void test_continue_fields(void) {
  static const char *const body =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"guess\":{\"durations\":[4.4975,2.7227,3.0513]},"
      "\"parameter\":\"ur\",\"range\":[0.3,1.5],\"fields\":[\"period\"]}";
  size_t ep;
  api_limits lim;
  api_response r;
  api_limits_default(&lim);
  ASSERT_EQ_INT(api_route("POST", "/continue", &ep), 200);
  api_handle(ep, body, strlen(body), &lim, NULL, &r);
  ASSERT_EQ_INT(r.status, 200);
  json_t *j = json_loads(r.body ? r.body : "", 0, NULL);
  json_t *pts = json_object_get(
      json_array_get(json_object_get(j, "branches"), 0), "points");
  ASSERT_TRUE(json_array_size(pts) > 10);
  for (size_t i = 0; i < json_array_size(pts); i++) {
    json_t *pt = json_array_get(pts, i);
    ASSERT_TRUE(json_object_size(pt) == 2 && json_object_get(pt, "value") &&
                json_object_get(pt, "period"));
  }
  json_decref(j);
  api_response_free(&r);
}

int main(int argc, char **argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: test_endpoints CASES_DIR SOURCE_DIR\n");
    return 2;
  }
  test_spec_and_table();
  test_cases_cover_table(argv[1]);
  test_problem_table();
  test_problem_pages(argv[2]);
  test_status_table();
  test_streams();
  test_batch();
  test_batch_text();
  test_continue_fields();
  TEST_DONE();
}
