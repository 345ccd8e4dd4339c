/*
 * test_http_explorer.c (CTest http_explorer): the explorer's page and assets
 * (media types, validators, the Content-Security-Policy), and CORS with and
 * without --cors-origin.
 */
#define _GNU_SOURCE
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fixture.h"

/* Whether the raw response @a raw has the header line "name: value". */
static int has_header_line(const char *raw, const char *name,
                           const char *value) {
  char line[160];
  snprintf(line, sizeof line, "\r\n%s: %s\r\n", name, value);
  const char *end = raw ? strstr(raw, "\r\n\r\n") : NULL;
  const char *h = raw ? strcasestr(raw, line) : NULL;
  return h && end && h < end;
}

/* EVIDENCE: docs/api/explorer.md: GET / is the page, its assets under
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

/* EVIDENCE: docs/api/explorer.md (CORS): with --cors-origin, a page of
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

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_explorer_files();
  fixture_daemon_stop(&d);
  test_cors();
  TEST_DONE();
}
