/*
 * test_http_connections.c (CTest http_connections): connections: the
 * per-address limit, the idle timeout, a request that does not arrive within
 * --request-timeout; SIGINT stops the daemon.
 */
#define _GNU_SOURCE
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fixture.h"

/* Has the server closed this connection?  Waits up to ms. */
static int closed_by_server(int fd, int ms) {
  struct pollfd p = {fd, POLLIN, 0};
  char c;
  if (poll(&p, 1, ms) <= 0)
    return 0;
  return recv(fd, &c, 1, 0) == 0;
}

/* EVIDENCE: docs/howto/limits.md (the table): per-IP connection limit and idle
 * timeout */
static void test_connection_limits(void) {
  daemon_proc d;
  const char *args[] = {"--per-ip-connections", "2", "--connection-timeout",
                        "1", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  int a = http_connect(d.port), b = http_connect(d.port);
  ASSERT_TRUE(a >= 0 && b >= 0);
  usleep(100000);
  /* a third connection from the same address is dropped at once */
  http_resp r;
  ASSERT_TRUE(http_do(d.port, "GET", "/health", NULL, NULL, &r) != 0);
  http_free(&r);
  /* idle connections are closed after the timeout */
  ASSERT_TRUE(closed_by_server(a, 4000));
  ASSERT_TRUE(closed_by_server(b, 4000));
  close(a);
  close(b);
  usleep(100000);
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  /* EVIDENCE: docs/howto/limits.md (Signals): SIGINT stops the daemon as
   * SIGTERM does */
  ASSERT_EQ_INT(daemon_stop_with(&d, SIGINT), 0);
  unlink(d.log_path);
}

/* EVIDENCE: docs/howto/limits.md (Architecture): a connection that does not
 * deliver its request within --request-timeout is closed, while others are
 * served */
static void test_slow_client(void) {
  daemon_proc d;
  const char *args[] = {"--request-timeout", "1", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  int slow[20];
  for (int i = 0; i < 20; i++) {
    slow[i] = http_connect(d.port);
    ASSERT_TRUE(slow[i] >= 0 && send(slow[i], "GET /hea", 8, 0) == 8);
  }
  double t0 = mono();
  http_resp r;
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  double dt = mono() - t0;
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  for (int i = 0; i < 20; i++) {
    /* a byte now and then does not keep it open past the deadline */
    ASSERT_TRUE(send(slow[i], "l", 1, MSG_NOSIGNAL) == 1);
  }
  ASSERT_TRUE(!closed_by_server(slow[0], 500));
  int closed = 0;
  for (int i = 0; i < 20; i++) {
    closed += closed_by_server(slow[i], 3000);
    close(slow[i]);
  }
  double total = mono() - t0;
  printf("slow clients: /health in %.2f ms beside 20 slow connections, all "
         "%d closed after %.2f s (deadline 1 s)\n",
         dt * 1e3, closed, total);
  ASSERT_EQ_INT(closed, 20);
  ASSERT_TRUE(metric(d.port, "stickslip_slow_closed_total") >= 20);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

int main(int argc, char **argv) {
  if (fixture_init(argc, argv))
    return 2;
  test_connection_limits();
  test_slow_client();
  TEST_DONE();
}
