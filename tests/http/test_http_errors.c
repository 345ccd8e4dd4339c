/*
 * test_http_errors.c (CTest http_errors): bad requests over HTTP: each gets
 * its problem+json answer (or libmicrohttpd's own page) and the daemon answers
 * /health afterwards.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixture.h"

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

/* GET /problems/<type> with @a accept (or none): the answer. */
static void get_page(const char *type, const char *accept, http_resp *r) {
  char req[512];
  int n = snprintf(req, sizeof req,
                   "GET /problems/%s HTTP/1.1\r\nHost: x\r\n%s%s%s"
                   "Connection: close\r\n\r\n",
                   type, accept ? "Accept: " : "", accept ? accept : "",
                   accept ? "\r\n" : "");
  ASSERT_TRUE(http_raw(PORT, req, (size_t)n, r) == 0);
}

/* EVIDENCE: RFC 9457 section 3.1.1: the type URI of a problem the daemon
 * answers is a page over HTTP, HTML for a browser and JSON otherwise, that
 * says how to fix the request; it is the type of the problem itself */
static void test_problem_pages(void) {
  http_resp r;
  json_t *p = expect_problem("a problem to look up", "POST", "/orbit", JSON,
                             "{\"params\":{\"chi\":2,\"eta\":4,\"us\":0.07,"
                             "\"ur\":0.6,\"V\":1}}",
                             422, "/problems/invalid-value", "/params/chi");
  const char *type = json_string_value(json_object_get(p, "type"));
  ASSERT_TRUE(type && !strncmp(type, "/problems/", 10));
  get_page(type ? type + 10 : "", NULL, &r);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(!strcmp(r.ctype, "application/json"));
  json_t *page = json_loads(r.body, 0, NULL);
  ASSERT_TRUE(type &&
              !strcmp(json_string_value(json_object_get(page, "type")), type));
  ASSERT_TRUE(json_integer_value(
                  json_array_get(json_object_get(page, "status"), 0)) == 422);
  ASSERT_TRUE(json_string_length(json_object_get(page, "fix")) > 0);
  ASSERT_TRUE(strstr(r.raw, "Vary: Accept\r\n") != NULL);
  json_decref(page);
  http_free(&r);
  /* a browser's Accept */
  get_page("invalid-value",
           "text/html,application/xhtml+xml,application/xml;q=0.9,*/*;q=0.8",
           &r);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(!strncmp(r.ctype, "text/html", 9));
  ASSERT_TRUE(strstr(r.body, "<h1>") && strstr(r.body, "0 &lt; chi &lt; 1"));
  http_free(&r);
  /* HTML refused (q=0), and curl's any type: JSON */
  get_page("invalid-value", "text/html;q=0, application/json", &r);
  ASSERT_TRUE(r.status == 200 && !strcmp(r.ctype, "application/json"));
  http_free(&r);
  get_page("invalid-value", "*/*", &r);
  ASSERT_TRUE(r.status == 200 && !strcmp(r.ctype, "application/json"));
  http_free(&r);
  json_decref(p);
  json_decref(expect_problem("no such problem type", "GET",
                             "/problems/Unknown-type", NULL, NULL, 404,
                             "/problems/not-found", NULL));
  json_decref(expect_problem("a page takes GET", "POST",
                             "/problems/invalid-value", JSON, "{}", 405,
                             "/problems/method-not-allowed", NULL));
}

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_bad_input();
  test_problem_pages();
  fixture_daemon_stop(&d);
  TEST_DONE();
}
