/*
 * test_http_shutdown.c (CTest http_shutdown): SIGTERM refuses new connections,
 * finishes the work in flight, answers what waits with 503 and exits 0; SIGHUP
 * is ignored.
 */
#define _GNU_SOURCE
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "fixture.h"

/* EVIDENCE: docs/howto/limits.md (Signals): SIGTERM refuses new connections,
 * finishes the work in flight, answers what waits with 503 and exits 0;
 * SIGHUP does not stop the daemon */
static void test_shutdown(void) {
  daemon_proc d;
  const char *args[] = {"--workers",
                        "1",
                        "--client-queue",
                        "4",
                        "--max-events",
                        "100000000",
                        "--max-horizon",
                        "1e8",
                        "--max-seconds",
                        "600",
                        "--drain",
                        "60",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  kill(d.pid, SIGHUP);
  usleep(100000);
  http_resp r;
  ASSERT_EQ_INT(http_do(d.port, "GET", "/health", NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  http_free(&r);
  int running = start(d.port, "/simulate", MEDIUM_SIM);
  usleep(50000);
  int waiting = start(d.port, "/simulate", MEDIUM_SIM);
  usleep(100000);
  kill(d.pid, SIGTERM);
  usleep(100000);
  int late = http_connect(d.port);
  ASSERT_TRUE(late < 0); /* refused: the listening socket is closed */
  if (late >= 0)
    close(late);
  http_resp a, b;
  ASSERT_EQ_INT(http_read(running, 60000, &a), 0);
  ASSERT_EQ_INT(http_read(waiting, 60000, &b), 0);
  printf("shutdown: running request %d, waiting request %d\n", a.status,
         b.status);
  ASSERT_EQ_INT(a.status, 200);
  ASSERT_EQ_INT(b.status, 503);
  ASSERT_TRUE(strstr(b.body, "shutting-down") != NULL);
  http_free(&a);
  http_free(&b);
  int st = 0;
  waitpid(d.pid, &st, 0);
  ASSERT_TRUE(WIFEXITED(st) && WEXITSTATUS(st) == 0);
  char *log = daemon_log(&d);
  ASSERT_TRUE(log && strstr(log, "SIGHUP ignored"));
  free(log);
  unlink(d.log_path);
}

int main(int argc, char **argv) {
  if (fixture_init(argc, argv))
    return 2;
  test_shutdown();
  TEST_DONE();
}
