/*
 * test_http_gzip.c (CTest http_gzip): answers gzipped for a client that
 * accepts it, whole, streamed and batched; none for one that refuses it or for
 * a small answer.
 */
#include <zlib.h>

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixture.h"

/* @a p (n bytes, gzip) inflated, NUL-terminated (malloc'd), or NULL. */
static char *gunzip(const char *p, size_t n, size_t *out_len) {
  z_stream zs;
  memset(&zs, 0, sizeof zs);
  if (inflateInit2(&zs, 15 + 16) != Z_OK)
    return NULL;
  size_t cap = 4 * n + 1024, len = 0;
  char *out = malloc(cap);
  zs.next_in = (Bytef *)(uintptr_t)p;
  zs.avail_in = (uInt)n;
  int rc = Z_OK;
  while (out && rc == Z_OK) {
    if (cap - len < 4096) {
      char *o = realloc(out, cap *= 2);
      if (!o) {
        free(out);
        out = NULL;
        break;
      }
      out = o;
    }
    zs.next_out = (Bytef *)out + len;
    zs.avail_out = (uInt)(cap - len - 1);
    rc = inflate(&zs, Z_NO_FLUSH);
    len = cap - 1 - zs.avail_out;
  }
  inflateEnd(&zs);
  if (rc != Z_STREAM_END || zs.avail_in) {
    free(out);
    return NULL;
  }
  out[len] = 0;
  *out_len = len;
  return out;
}

/* EVIDENCE: docs/howto/operations.md: gzip for a client that accepts it, whole
 * answers and streamed ones alike, and none for one that refuses it or for
 * a small answer. */
static void test_gzip(void) {
  http_resp plain, gz;
  char v[128];
  size_t n = 0;
  /* a whole answer */
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json", "", NULL, &plain), 0);
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json",
                         "Accept-Encoding: gzip\r\n", NULL, &gz),
                0);
  ASSERT_TRUE(header_of(gz.raw, "Content-Encoding", v, sizeof v) &&
              !strcmp(v, "gzip"));
  ASSERT_TRUE(header_of(gz.raw, "Vary", v, sizeof v) &&
              !strcmp(v, "Accept-Encoding"));
  ASSERT_TRUE(header_of(gz.raw, "ETag", v, sizeof v) && strstr(v, "-gzip\""));
  char *text = gunzip(gz.body, gz.len, &n);
  ASSERT_TRUE(text && n == plain.len && !memcmp(text, plain.body, n));
  printf("gzip: /openapi.json %zu -> %zu bytes\n", plain.len, gz.len);
  free(text);
  /* its gzip validator gets 304 */
  char inm[200];
  snprintf(inm, sizeof inm, "Accept-Encoding: gzip\r\nIf-None-Match: %s\r\n",
           v);
  http_free(&gz);
  ASSERT_EQ_INT(raw_with(PORT, "GET", "/openapi.json", inm, NULL, &gz), 0);
  ASSERT_EQ_INT(gz.status, 304);
  http_free(&gz);
  http_free(&plain);
  /* a streamed answer (over the streaming threshold) */
  const char *sim =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
      "\"initial\":[1.2739277342427062,4.362927734242709,-0.8074871367243069,"
      "1.0],\"t_end\":100,\"samples\":{\"n\":2000,\"from\":0,\"to\":100}}";
  ASSERT_EQ_INT(raw_with(PORT, "POST", "/simulate", "", sim, &plain), 0);
  ASSERT_EQ_INT(raw_with(PORT, "POST", "/simulate",
                         "Accept-Encoding: br, gzip;q=0.5\r\n", sim, &gz),
                0);
  ASSERT_EQ_INT(gz.status, 200);
  ASSERT_TRUE(plain.chunked && gz.chunked);
  ASSERT_TRUE(header_of(gz.raw, "Content-Encoding", v, sizeof v) &&
              !strcmp(v, "gzip"));
  text = gunzip(gz.body, gz.len, &n);
  ASSERT_TRUE(text && n == plain.len && !memcmp(text, plain.body, n));
  printf("gzip: a 2000-sample /simulate %zu -> %zu bytes, streamed\n",
         plain.len, gz.len);
  free(text);
  http_free(&gz);
  http_free(&plain);
  /* a batch: its NDJSON gzipped piece by piece, each flushed */
  const char *bat =
      "{\"requests\":[{\"id\":\"s\",\"path\":\"/simulate\",\"body\":"
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"initial\":[1.27,4.36,-0.8,1],\"t_end\":50,\"samples\":"
      "{\"n\":300}}},{\"id\":\"o\",\"path\":\"/orbit\",\"body\":{\"params\":"
      "{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
      "\"guess\":{\"durations\":[4.4975,2.7227,3.0513]}}}]}";
  ASSERT_EQ_INT(
      raw_with(PORT, "POST", "/batch", "Accept-Encoding: gzip\r\n", bat, &gz),
      0);
  ASSERT_EQ_INT(gz.status, 200);
  ASSERT_TRUE(header_of(gz.raw, "Content-Encoding", v, sizeof v) &&
              !strcmp(v, "gzip"));
  text = gunzip(gz.body, gz.len, &n);
  ASSERT_TRUE(text != NULL);
  int lines = 0, ok_lines = 0;
  for (char *l = text ? strtok(text, "\n") : NULL; l; l = strtok(NULL, "\n")) {
    json_t *j = json_loads(l, 0, NULL);
    lines++;
    ok_lines += j && (json_integer_value(json_object_get(j, "status")) == 200 ||
                      json_is_true(json_object_get(j, "done")));
    json_decref(j);
  }
  ASSERT_EQ_INT(lines, 3);
  ASSERT_EQ_INT(ok_lines, 3);
  printf("gzip: a /batch of 2 items, %zu -> %zu bytes\n", n, gz.len);
  free(text);
  http_free(&gz);
  /* refused (q=0), or too small to gain */
  const char *no[][2] = {{"/openapi.json", "Accept-Encoding: gzip;q=0\r\n"},
                         {"/openapi.json", "Accept-Encoding: xgzip\r\n"},
                         {"/health", "Accept-Encoding: gzip\r\n"}};
  for (int i = 0; i < 3; i++) {
    ASSERT_EQ_INT(raw_with(PORT, "GET", no[i][0], no[i][1], NULL, &gz), 0);
    ASSERT_EQ_INT(gz.status, 200);
    ASSERT_TRUE(!header_of(gz.raw, "Content-Encoding", v, sizeof v));
    ASSERT_TRUE(gz.len == strlen(gz.body));
    http_free(&gz);
  }
}

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_gzip();
  fixture_daemon_stop(&d);
  TEST_DONE();
}
