/*
 * test_http_pool.c (CTest http_pool): the computation pool: per-client queues
 * served round robin, a full queue refused, a hang-up cancelling its work, and
 * which client a request is behind a trusted proxy.
 */
#define _GNU_SOURCE
#include <math.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fixture.h"

/* EVIDENCE: docs/howto/limits.md (Architecture): per-client queues served round
 * robin, a full queue answered 503 at once, another client's cheap work not
 * kept waiting by a client's long work, and a client that hangs up stops its
 * work */
static void test_pool(void) {
  daemon_proc d;
  const char *args[] = {"--workers",
                        "2",
                        "--client-workers",
                        "1",
                        "--client-queue",
                        "2",
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
  /* client A (127.0.0.1): one long computation runs, two wait, three are
   * refused at once */
  int fd[6];
  for (int i = 0; i < 6; i++) {
    fd[i] = start(d.port, "/simulate", LONG_SIM);
    usleep(20000);
  }
  usleep(200000);
  int refused = 0, pending = 0;
  for (int i = 0; i < 6; i++) {
    struct pollfd p = {fd[i], POLLIN, 0};
    if (poll(&p, 1, 0) > 0) {
      http_resp r;
      ASSERT_EQ_INT(http_read(fd[i], 2000, &r), 0);
      ASSERT_EQ_INT(r.status, 503);
      ASSERT_TRUE(strcmp(r.retry_after, "1") == 0);
      http_free(&r);
      fd[i] = -1;
      refused++;
    } else {
      pending++;
    }
  }
  printf("pool: 6 long requests from one client: %d waiting or running, %d "
         "refused at once\n",
         pending, refused);
  ASSERT_EQ_INT(refused, 3);
  /* a /health meanwhile, from A itself */
  http_resp r;
  double t0 = mono();
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  double dt = mono() - t0;
  ASSERT_EQ_INT(r.status, 200);
  json_t *h = json_loads(r.body, 0, NULL);
  long inflight = (long)num(h, "/in_flight");
  json_decref(h);
  http_free(&r);
  printf("pool: /health in %.2f ms with %ld requests in flight\n", dt * 1e3,
         inflight);
  ASSERT_TRUE(inflight >= 3);
  /* client B (127.0.0.2): cheap computations are not kept waiting */
  double worst = 0;
  for (int i = 0; i < 20; i++) {
    probe pb = {d.port, 0, "127.0.0.2", 0};
    cheap_probe(&pb);
    ASSERT_EQ_INT(pb.status, 200);
    worst = fmax(worst, pb.seconds);
  }
  printf("pool: 20 cheap /stability from another client while the first "
         "keeps its long work in flight: slowest %.2f ms\n",
         worst * 1e3);
  ASSERT_TRUE(worst < 1.0);
  /* A hangs up: its waiting work is dropped, its running work stops */
  t0 = mono();
  for (int i = 0; i < 6; i++)
    if (fd[i] >= 0)
      close(fd[i]);
  double cancelled = 0;
  while (mono() - t0 < 5 &&
         (cancelled = metric(d.port, "stickslip_cancelled_total")) < 3)
    usleep(10000);
  double t_stop = mono() - t0;
  usleep(300000);
  double cpu1 = cpu_seconds(d.pid);
  usleep(500000);
  double cpu2 = cpu_seconds(d.pid);
  printf("pool: after the hang-up, 3 computations cancelled in %.0f ms; "
         "then %.3f CPU-s in 0.5 s\n",
         t_stop * 1e3, cpu2 - cpu1);
  ASSERT_TRUE(cancelled == 3);
  ASSERT_TRUE(cpu2 - cpu1 < 0.1);
  /* A's slot is free again at once */
  probe pa = {d.port, 0, "127.0.0.1", 0};
  cheap_probe(&pa);
  ASSERT_EQ_INT(pa.status, 200);
  ASSERT_TRUE(pa.seconds < 1.0);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  char *log = daemon_log(&d);
  ASSERT_TRUE(log && strstr(log, "\"method\":\"GET\",\"path\":\"/health\","
                                 "\"status\":200,"));
  free(log);
  unlink(d.log_path);
}

/* A long /simulate sent with X-Forwarded-For: @a xff; its socket. */
static int start_forwarded(int port, const char *xff) {
  char req[1024];
  int n = snprintf(req, sizeof req,
                   "POST /simulate HTTP/1.1\r\nHost: x\r\nContent-Type: "
                   "application/json\r\nX-Forwarded-For: %s\r\n"
                   "Content-Length: %zu\r\n\r\n%s",
                   xff, strlen(LONG_SIM), LONG_SIM);
  return http_send(port, req, (size_t)n);
}

/* The status of the answer on @a fd within @a ms, or 0 (none yet). */
static int status_within(int fd, int ms) {
  char head[16] = {0};
  struct pollfd p = {fd, POLLIN, 0};
  if (poll(&p, 1, ms) > 0 && recv(fd, head, 12, 0) == 12)
    return atoi(head + 9);
  return 0;
}

/* Which client a request is, with and without --trusted-proxy: with one
 * computation per client and no waiting, a second long request of the same
 * client gets 503 at once, another client's runs.  Behind a trusted proxy
 * the client is the first address of X-Forwarded-For; from any other peer
 * the header is ignored. */
static void run_forwarded(int trusted, const char *xff1, const char *xff2,
                          int want2) {
  daemon_proc d;
  const char *args[] = {"--client-workers",
                        "1",
                        "--client-queue",
                        "0",
                        "--workers",
                        "2",
                        "--max-events",
                        "1000000000",
                        "--max-horizon",
                        "1e10",
                        "--max-seconds",
                        "600",
                        "--trusted-proxy",
                        trusted ? "127.0.0.1" : "127.0.0.9",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  int a = start_forwarded(d.port, xff1);
  usleep(200000);
  int b = start_forwarded(d.port, xff2);
  int sb = status_within(b, 500);
  if (sb != want2)
    printf("forwarded: trusted %d, second from %s: %d, want %d\n", trusted,
           xff2, sb, want2);
  ASSERT_EQ_INT(sb, want2);
  close(a);
  close(b);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* EVIDENCE: docs/howto/limits.md: --trusted-proxy */
static void test_forwarded(void) {
  const char *first = "10.0.0.1, 127.0.0.1";
  run_forwarded(1, first, "10.0.0.2", 0);    /* another client: it runs */
  run_forwarded(1, first, " 10.0.0.1", 503); /* the same client */
  /* an untrusted peer: the header is ignored, both are 127.0.0.1 */
  run_forwarded(0, first, "10.0.0.2", 503);
  /* not an address: the client is the peer */
  run_forwarded(1, "unknown", "::1x", 503);
  printf("forwarded: clients told apart by X-Forwarded-For from a trusted "
         "proxy only\n");
}

int main(int argc, char **argv) {
  if (fixture_init(argc, argv))
    return 2;
  test_pool();
  test_forwarded();
  TEST_DONE();
}
