/*
 * test_http_framing.c (CTest http_framing): requests whose framing is
 * ambiguous are refused and their connection closed; the size of the header
 * block.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixture.h"

/* EVIDENCE: docs/howto/limits.md (Architecture): two Content-Length headers,
 * Content-Length with Transfer-Encoding, or two Host headers are refused
 * with 400 and the connection is closed (none of these requests asks for
 * Connection: close).  A GET with a body is answered (stated nowhere). */
static void test_framing(void) {
  static const char *bad[] = {
      "POST /orbit HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
      "Content-Length: 2\r\nContent-Length: 60\r\n\r\n{}",
      "POST /orbit HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
      "Content-Length: 7\r\nTransfer-Encoding: chunked\r\n\r\n2\r\n{}\r\n0"
      "\r\n\r\n",
      "GET /health HTTP/1.1\r\nHost: x\r\nHost: y\r\n\r\n",
  };
  for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
    expect_problem_raw("smuggling framing", bad[i], strlen(bad[i]), 400,
                       "/problems/bad-request", 0);
  const char *get_body =
      "GET /health HTTP/1.1\r\nHost: x\r\nConnection: close\r\n"
      "Content-Length: 5\r\n\r\nhello";
  http_resp r;
  ASSERT_EQ_INT(http_raw(PORT, get_body, strlen(get_body), &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  /* the header block: 24 KiB are read, 40 KiB refused (README: 32 KiB) */
  for (int big = 0; big < 2; big++) {
    size_t n = big ? 40000 : 24000;
    char *req = malloc(n + 128);
    int k = snprintf(req, 128,
                     "GET /health HTTP/1.1\r\nHost: x\r\nConnection: "
                     "close\r\nX-Big: ");
    memset(req + k, 'a', n);
    memcpy(req + k + n, "\r\n\r\n", 5);
    ASSERT_EQ_INT(http_raw(PORT, req, (size_t)k + n + 4, &r), 0);
    ASSERT_EQ_INT(r.status, big ? 431 : 200);
    http_free(&r);
    free(req);
  }
}

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_framing();
  fixture_daemon_stop(&d);
  TEST_DONE();
}
