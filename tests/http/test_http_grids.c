/*
 * test_http_grids.c (CTest http_grids): /basins and /map inside the limits
 * whatever their shape.  A far slice, whose every cell simulates all of its
 * max_returns returns without landing (64 events a return), is answered 422
 * within 1.5 times --max-seconds and stops within 0.2 s of a hang-up; the
 * threads of a /basins and of a /map count against the client's workers.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fixture.h"

/* x1 and x2 a million from the equilibrium: no cell returns to Sigma0
 * within its max_returns * 64 events (500 returns: 16 ms a cell, 84 s for
 * the row of 4096 when only rows were polled; 100000 returns: seconds a
 * cell); in @a rows rows (threads take a row at a time). */
#define FAR(rows, max_returns)                                                 \
  "{" PAPER ",\"axes\":[{\"variable\":\"x1\",\"from\":-1e6,\"to\":1e6,"        \
  "\"n\":" rows                                                                \
  "},{\"variable\":\"x2\",\"from\":-1e6,\"to\":1e6,\"n\":4096}],"              \
  "\"state\":{\"v1\":0,\"v2\":1},\"max_returns\":" max_returns "}"

/* A map whose every cell is a full search: minutes of work. */
#define WIDE_MAP                                                               \
  "{" PAPER ",\"axes\":[{\"parameter\":\"chi\",\"from\":0.1,\"to\":0.5,"       \
  "\"n\":100},{\"parameter\":\"eta\",\"from\":1,\"to\":8,\"n\":100}],"         \
  "\"search_every\":1,\"effort\":3}"

/* The threads of process @a pid now. */
static int threads_of(pid_t pid) {
  char path[64];
  snprintf(path, sizeof path, "/proc/%d/task", (int)pid);
  DIR *dir = opendir(path);
  if (!dir)
    return -1;
  int n = 0;
  for (struct dirent *e; (e = readdir(dir));)
    n += e->d_name[0] != '.';
  closedir(dir);
  return n;
}

/* EVIDENCE: docs/howto/limits.md: a computation's time, encoding included, is
 * bounded by --max-seconds whatever the request's shape.  Before the budget
 * was polled inside a cell this answer took 84 s. */
static void test_budget(void) {
  daemon_proc d;
  const char *args[] = {"--max-seconds", "2", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;
  double t0 = mono();
  http_resp r;
  ASSERT_EQ_INT(http_do(d.port, "POST", "/basins", JSON, FAR("1", "500"), &r),
                0);
  double t = mono() - t0;
  json_t *p =
      problem_body("far slice", &r, 422, "/problems/limit-exceeded", NULL);
  if (p) {
    const char *limit = json_string_value(json_object_get(p, "limit"));
    ASSERT_TRUE(limit && strcmp(limit, "max_seconds") == 0);
  }
  json_decref(p);
  http_free(&r);
  printf("grids: the far slice answered 422 after %.2f s of a 2 s budget\n", t);
  ASSERT_TRUE(t < 1.5 * 2);
  fixture_daemon_stop(&d);
}

/* EVIDENCE: DESIGN section 5 "a client that hangs up stops its
 * computation": the far slice at 100000 returns a cell, cut once it has
 * computed for 1 CPU-s (its orbit search done, its first cell under way:
 * 1 s on an idle machine, more on a loaded one).  Before the cancel flag was
 * polled inside a cell it burned 112 CPU-s. */
static void test_hang_up(void) {
  daemon_proc d;
  const char *args[] = {"--max-seconds", "600", NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;
  double cancelled0 = metric(d.port, "stickslip_cancelled_total");
  double cpu0 = cpu_seconds(d.pid), t0 = mono(), busy = 0;
  int fd = start(d.port, "/basins", FAR("1", "100000"));
  while (mono() - t0 < 20 && (busy = cpu_seconds(d.pid) - cpu0) < 1)
    usleep(10000);
  close(fd);
  double t1 = mono();
  usleep(200000);
  double cpu1 = cpu_seconds(d.pid);
  usleep(500000);
  double cpu2 = cpu_seconds(d.pid);
  double cancelled = metric(d.port, "stickslip_cancelled_total");
  printf("grids: the far slice cut after %.2f CPU-s in %.2f s: %.3f CPU-s in "
         "the 0.5 s from 0.2 s after\n",
         busy, t1 - t0, cpu2 - cpu1);
  ASSERT_TRUE(busy >= 1);
  ASSERT_TRUE(cpu2 - cpu1 < 0.05);
  ASSERT_TRUE(cancelled == cancelled0 + 1);
  health_ok("a far slice cut");
  fixture_daemon_stop(&d);
}

/* The most threads beyond its @a idle ones the daemon @a d has while it
 * works on @a path's @a body, sampled for 3 s (the cells start after the
 * orbit search, which under the sanitizers and a loaded machine has taken
 * over 0.5 s) or until there are @a enough, then the request cut. */
static int threads_while(const daemon_proc *d, const char *path,
                         const char *body, int enough) {
  int idle = threads_of(d->pid);
  int fd = start(d->port, path, body), most = 0;
  double t0 = mono();
  while (mono() - t0 < 3 && (enough == 0 || most < enough)) {
    int n = threads_of(d->pid) - idle;
    most = n > most ? n : most;
    usleep(2000);
  }
  close(fd);
  usleep(300000);
  return most;
}

/* EVIDENCE: docs/howto/limits.md: a client computes on at most --client-workers
 * threads, a /map's or a /basins' own threads included, and the pool on at
 * most --workers.  With a cap of 1 the request's own worker is all it gets
 * (--map-threads 2 used to start a second); with a cap of 2 it borrows one
 * more, and another client still finds the third worker. */
static void test_threads(void) {
  for (int cap = 1; cap <= 2; cap++) {
    daemon_proc d;
    const char *args[] = {"--workers",
                          cap == 1 ? "2" : "3",
                          "--client-workers",
                          cap == 1 ? "1" : "2",
                          "--map-threads",
                          "4",
                          "--max-seconds",
                          "600",
                          NULL};
    ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
    PORT = d.port;
    health_ok("start");
    int more = threads_while(&d, "/basins", FAR("4", "100000"), cap - 1);
    printf("grids: client cap %d: /basins on %d threads beyond the idle "
           "daemon's\n",
           cap, more);
    ASSERT_EQ_INT(more, cap - 1);
    more = threads_while(&d, "/map", WIDE_MAP, cap - 1);
    printf("grids: client cap %d: /map on %d threads beyond the idle "
           "daemon's\n",
           cap, more);
    ASSERT_EQ_INT(more, cap - 1);
    /* another client is served while a /basins holds what it may */
    int fd = start(d.port, "/basins", FAR("4", "100000"));
    usleep(200000);
    probe pb = {d.port, 0, "127.0.0.2", 0};
    cheap_probe(&pb);
    http_set_source(NULL);
    ASSERT_EQ_INT(pb.status, 200);
    printf("grids: client cap %d: another client's /stability in %.1f ms "
           "meanwhile\n",
           cap, pb.seconds * 1e3);
    ASSERT_TRUE(pb.seconds < 1.0);
    close(fd);
    usleep(300000);
    health_ok("the grids cut");
    fixture_daemon_stop(&d);
  }
}

int main(int argc, char **argv) {
  int rc = fixture_init(argc, argv);
  if (rc)
    return rc;
  test_budget();
  test_hang_up();
  test_threads();
  TEST_DONE();
}
