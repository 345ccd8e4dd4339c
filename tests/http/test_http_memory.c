/*
 * test_http_memory.c (CTest http_memory): the memory budget of the answers in
 * flight (--memory-budget), and large answers streamed.
 */
#define _GNU_SOURCE
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "fixture.h"

/* VmHWM (peak resident set) of a process, MiB; -1 when unknown. */
static double peak_rss_mib(pid_t pid) {
  char path[64], line[256];
  double v = -1;
  snprintf(path, sizeof path, "/proc/%d/status", (int)pid);
  FILE *f = fopen(path, "r");
  while (f && fgets(line, sizeof line, f))
    if (strncmp(line, "VmHWM:", 6) == 0)
      v = atof(line + 6) / 1024;
  if (f)
    fclose(f);
  return v;
}

/* 100000 samples and some 2900 events: a 10.7 MB answer whose arrays hold
 * about 4.3 MB in the daemon. */
static const char *BIG_SIM = "{" PAPER ",\"initial\":" X0 ",\"t_end\":10000,"
                             "\"samples\":{\"n\":100000}}";

/* EVIDENCE: docs/howto/limits.md: --memory-budget; large answers are streamed
 * (chunked) from the result, and what answers in flight hold is bounded:
 * a client that never reads gets 503 once its share of the budget is
 * spent */
static void test_memory(void) {
  daemon_proc d;
  const char *args[] = {"--memory-budget",  "16", "--workers", "2",
                        "--client-workers", "2",  NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  /* a reader gets the whole answer, chunked */
  http_resp r;
  ASSERT_EQ_INT(http_do(d.port, "POST", "/simulate", JSON, BIG_SIM, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(r.chunked);
  json_t *j = json_loads(r.body, 0, NULL);
  ASSERT_TRUE(j != NULL);
  ASSERT_EQ_INT(
      json_array_size(json_object_get(json_object_get(j, "samples"), "mode")),
      100000);
  ASSERT_TRUE(json_array_size(json_object_get(j, "events")) > 1000);
  ASSERT_NEAR(num(j, "/final/t"), 10000, 0);
  json_decref(j);
  http_free(&r);
  /* 16 connections of one client that never read: each answer holds
   * ~4.3 MB, so after two of them the client's share of the budget of 16
   * MiB (half of it, the client being alone) is spent */
  enum { N = 16 };
  int fd[N], ok = 0, busy = 0;
  for (int i = 0; i < N; i++) {
    fd[i] = start(d.port, "/simulate", BIG_SIM);
    ASSERT_TRUE(fd[i] >= 0);
    setsockopt(fd[i], SOL_SOCKET, SO_RCVBUF, &(int){4096}, sizeof(int));
  }
  /* every one gets the head of its answer: 200 and the start of the
   * stream, or 503 */
  for (int i = 0; i < N; i++) {
    char head[16] = {0};
    struct pollfd p = {fd[i], POLLIN, 0};
    if (poll(&p, 1, 30000) > 0 && recv(fd[i], head, 12, 0) == 12) {
      ok += strncmp(head + 9, "200", 3) == 0;
      busy += strncmp(head + 9, "503", 3) == 0;
    }
  }
  double held = metric(d.port, "stickslip_memory_held_bytes") / 1048576;
  double peak = metric(d.port, "stickslip_memory_held_peak_bytes") / 1048576;
  double rss = peak_rss_mib(d.pid);
  printf("memory: 16 non-reading clients, budget 16 MiB: %d answers "
         "(held %.1f MiB, peak %.1f), %d refused 503; peak RSS %.1f MiB\n",
         ok, held, peak, busy, rss);
  ASSERT_EQ_INT(ok + busy, N);
  ASSERT_TRUE(busy >= N / 2);
  ASSERT_TRUE(ok >= 2);
  /* what may be admitted past the share: the answers being computed when
   * it was spent, at most one per worker */
  ASSERT_TRUE(peak <= 16 / 2 + 2 * 4.5);
  ASSERT_TRUE(held >= 16 / 2 && held <= peak);
  ASSERT_TRUE(metric(d.port, "stickslip_rejected_memory_total") >= busy);
  for (int i = 0; i < N; i++)
    close(fd[i]);
  /* hang-ups give the bytes back */
  double t0 = mono();
  while (metric(d.port, "stickslip_memory_held_bytes") > 0 && mono() - t0 < 5)
    usleep(20000);
  ASSERT_NEAR(metric(d.port, "stickslip_memory_held_bytes"), 0, 0);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

int main(int argc, char **argv) {
  if (fixture_init(argc, argv))
    return 2;
  test_memory();
  TEST_DONE();
}
