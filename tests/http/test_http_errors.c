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

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_bad_input();
  fixture_daemon_stop(&d);
  TEST_DONE();
}
