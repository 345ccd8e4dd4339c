/*
 * test_store.c: the job store (server/store.h), the same checks against
 * each backend: test_store URI, with URI sqlite:PATH (a fresh file) or
 * postgresql://... (its stickslip_* tables are dropped first).  For
 * PostgreSQL, test_store @FILE reads the URI from FILE, which the CTest
 * fixture pg (scripts/pg-throwaway.sh) writes; a missing file is a skip
 * (77), unless SS_REQUIRE_PG is set (CI), where it is a failure.
 *
 * Jobs, paging, bodies; claims by stage, by lease, oldest job first;
 * renew and complete under a lease, and nothing written without it;
 * results compressed and not, byte for byte; fail, dismiss, counts,
 * expire; four claimers on two handles (two replicas) taking every chunk of
 * one job exactly once; and for SQLite, the file deleted or opened
 * read-only: every write fails.
 */
#define _GNU_SOURCE /* unshare */
#include <errno.h>
#include <libpq-fe.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "store.h"
#include "test.h"

static const char *uri;
static char uri_buf[1024];

static store *open_store(void) {
  store *s = NULL;
  char why[512];
  if (store_open(uri, &s, why, sizeof why) != 0) {
    fprintf(stderr, "cannot open %s: %s\n", uri, why);
    exit(1);
  }
  return s;
}

static void make_job(store_job *j, const char *id, const char *path,
                     double created) {
  memset(j, 0, sizeof *j);
  snprintf(j->id, sizeof j->id, "%s", id);
  snprintf(j->path, sizeof j->path, "%s", path);
  j->created = created;
}

static const char *ID_A = "aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa1";
static const char *ID_B = "bbbbbbbbbbbbbbbbbbbbbbbbbbbbbbb2";
static const char *ID_C = "ccccccccccccccccccccccccccccccc3";

static void test_jobs(store *s) {
  store_chunk a[3] = {{0, 5}, {0, 7}, {1, 0}}, b[1] = {{0, 1}},
              c[2] = {{0, 2}, {0, 2}};
  store_job j;
  const char body_a[] = "{\"requests\":[1,\0 2]}"; /* a NUL inside */
  make_job(&j, ID_A, "/batch", 1000);
  ASSERT_EQ_INT(store_submit(s, &j, body_a, sizeof body_a, a, 3), 0);
  make_job(&j, ID_B, "/orbit", 1001);
  ASSERT_EQ_INT(store_submit(s, &j, "{}", 2, b, 1), 0);
  make_job(&j, ID_C, "/map", 1002);
  ASSERT_EQ_INT(store_submit(s, &j, "{\"axes\":[]}", 11, c, 2), 0);
  /* the same id twice is refused */
  make_job(&j, ID_C, "/map", 1003);
  ASSERT_EQ_INT(store_submit(s, &j, "{}", 2, c, 2), STORE_ERROR);

  store_job g;
  ASSERT_EQ_INT(store_get(s, ID_A, &g), 0);
  ASSERT_TRUE(!strcmp(g.id, ID_A) && !strcmp(g.path, "/batch"));
  ASSERT_EQ_INT(g.status, STORE_ACCEPTED);
  ASSERT_EQ_INT(g.chunks, 3);
  ASSERT_EQ_INT(g.items, 12);
  ASSERT_EQ_INT(g.chunks_done + g.items_done, 0);
  ASSERT_NEAR(g.created, 1000, 0);
  ASSERT_NEAR(g.started + g.finished, 0, 0);
  ASSERT_EQ_INT(store_get(s, "ffffffffffffffffffffffffffffffff", &g),
                STORE_NONE);

  char *body = NULL;
  size_t len = 0;
  ASSERT_EQ_INT(store_body(s, ID_A, &body, &len), 0);
  ASSERT_TRUE(len == sizeof body_a && !memcmp(body, body_a, len));
  free(body);

  store_job list[2];
  size_t n = 0;
  long total = 0;
  ASSERT_EQ_INT(store_list(s, 0, 2, list, &n, &total), 0);
  ASSERT_TRUE(n == 2 && total == 3);
  ASSERT_TRUE(n == 2 && !strcmp(list[0].id, ID_C) && !strcmp(list[1].id, ID_B));
  ASSERT_EQ_INT(store_list(s, 2, 2, list, &n, &total), 0);
  ASSERT_TRUE(n == 1 && total == 3 && !strcmp(list[0].id, ID_A));
  ASSERT_EQ_INT(store_list(s, 5, 2, list, &n, &total), 0);
  ASSERT_TRUE(n == 0 && total == 3);
}

/* Claims: the oldest job first, by stage, by lease. */
static void test_claims(store *s) {
  char id[STORE_ID_LEN + 1];
  long k = -1;
  ASSERT_EQ_INT(store_claim(s, "r1", 2000, 10, id, &k), 0);
  ASSERT_TRUE(!strcmp(id, ID_A) && k == 0);
  store_job g;
  store_get(s, ID_A, &g);
  ASSERT_EQ_INT(g.status, STORE_RUNNING);
  ASSERT_NEAR(g.started, 2000, 0);
  ASSERT_EQ_INT(store_claim(s, "r1", 2000, 10, id, &k), 0);
  ASSERT_TRUE(!strcmp(id, ID_A) && k == 1);
  /* A's chunk 2 is of stage 1: B's chunk comes next */
  ASSERT_EQ_INT(store_claim(s, "r2", 2001, 1000, id, &k), 0);
  ASSERT_TRUE(!strcmp(id, ID_B) && k == 0);
  /* C's two chunks, then nothing */
  ASSERT_EQ_INT(store_claim(s, "r2", 2001, 1000, id, &k), 0);
  ASSERT_TRUE(!strcmp(id, ID_C) && k == 0);
  ASSERT_EQ_INT(store_claim(s, "r2", 2001, 1000, id, &k), 0);
  ASSERT_TRUE(!strcmp(id, ID_C) && k == 1);
  ASSERT_EQ_INT(store_claim(s, "r2", 2001, 1000, id, &k), STORE_NONE);

  /* renew: the owner, not another */
  ASSERT_EQ_INT(store_renew(s, "r1", ID_A, 0, 2020), 0);
  ASSERT_EQ_INT(store_renew(s, "r2", ID_A, 0, 2020), STORE_NONE);
  /* A's chunk 1 (lease to 2010) lapses; chunk 0 was renewed to 2020 */
  ASSERT_EQ_INT(store_claim(s, "r3", 2015, 10, id, &k), 0);
  ASSERT_TRUE(!strcmp(id, ID_A) && k == 1);
  /* r1 has lost it: its result is not written, r3's is */
  ASSERT_EQ_INT(store_complete(s, "r1", ID_A, 1, "old", 3, 2016), STORE_NONE);
  char *buf = NULL;
  size_t len = 0;
  ASSERT_EQ_INT(store_result(s, ID_A, 1, &buf, &len), STORE_NONE);
  ASSERT_EQ_INT(store_renew(s, "r1", ID_A, 1, 2030), STORE_NONE);
  ASSERT_EQ_INT(store_complete(s, "r3", ID_A, 1, "new\n", 4, 2016), 0);
  ASSERT_EQ_INT(store_result(s, ID_A, 1, &buf, &len), 0);
  ASSERT_TRUE(len == 4 && !memcmp(buf, "new\n", 4));
  free(buf);
  /* stored once: a second complete is refused */
  ASSERT_EQ_INT(store_complete(s, "r3", ID_A, 1, "again", 5, 2017), STORE_NONE);
  store_get(s, ID_A, &g);
  ASSERT_TRUE(g.chunks_done == 1 && g.items_done == 7);
  ASSERT_EQ_INT(g.status, STORE_RUNNING);

  /* stage 1 waits for chunk 0; then A's last chunk, compressed */
  ASSERT_EQ_INT(store_claim(s, "r4", 2017, 10, id, &k), STORE_NONE);
  size_t big = 200000;
  char *text = malloc(big);
  for (size_t i = 0; i < big; i++)
    text[i] = "{\"index\":[1,2],\"orbits\":[]}\n"[i % 29];
  ASSERT_EQ_INT(store_complete(s, "r1", ID_A, 0, text, big, 2018), 0);
  ASSERT_EQ_INT(store_claim(s, "r4", 2018, 10, id, &k), 0);
  ASSERT_TRUE(!strcmp(id, ID_A) && k == 2);
  ASSERT_EQ_INT(store_result(s, ID_A, 0, &buf, &len), 0);
  ASSERT_TRUE(len == big && !memcmp(buf, text, big) && buf[len] == 0);
  free(buf);
  /* incompressible bytes, stored as they are */
  for (size_t i = 0; i < 5000; i++)
    text[i] = (char)(rand() & 0xff);
  ASSERT_EQ_INT(store_complete(s, "r4", ID_A, 2, text, 5000, 2019.5), 0);
  ASSERT_EQ_INT(store_result(s, ID_A, 2, &buf, &len), 0);
  ASSERT_TRUE(len == 5000 && !memcmp(buf, text, 5000));
  free(buf);
  free(text);
  store_get(s, ID_A, &g);
  ASSERT_EQ_INT(g.status, STORE_SUCCESSFUL);
  ASSERT_TRUE(g.chunks_done == 3 && g.items_done == 12);
  ASSERT_NEAR(g.finished, 2019.5, 0);
  ASSERT_EQ_INT(store_claim(s, "r4", 2019, 10, id, &k), STORE_NONE);
}

static void test_fail_dismiss(store *s) {
  const char *prob = "{\"status\":422,\"type\":\"/problems/limit\"}";
  /* B fails: its problem is kept, its chunk is no longer stored */
  ASSERT_EQ_INT(
      store_fail(s, ID_B, "over the time", 422, prob, strlen(prob), 2100), 0);
  ASSERT_EQ_INT(store_fail(s, ID_B, "again", 500, "x", 1, 2101), STORE_NONE);
  store_job g;
  store_get(s, ID_B, &g);
  ASSERT_EQ_INT(g.status, STORE_FAILED);
  ASSERT_TRUE(!strcmp(g.message, "over the time"));
  ASSERT_NEAR(g.finished, 2100, 0);
  int status = 0;
  char *body = NULL;
  size_t len = 0;
  ASSERT_EQ_INT(store_problem(s, ID_B, &status, &body, &len), 0);
  ASSERT_TRUE(status == 422 && len == strlen(prob) && !memcmp(body, prob, len));
  free(body);
  ASSERT_EQ_INT(store_problem(s, ID_A, &status, &body, &len), STORE_NONE);
  ASSERT_EQ_INT(store_complete(s, "r2", ID_B, 0, "late", 4, 2102), STORE_NONE);

  /* C dismissed while running: results gone, no claims, its row kept */
  ASSERT_EQ_INT(store_complete(s, "r2", ID_C, 0, "cell\n", 5, 2103), 0);
  long by[5], pending = -1;
  ASSERT_EQ_INT(store_counts(s, by, &pending), 0);
  ASSERT_TRUE(by[STORE_RUNNING] == 1 && by[STORE_SUCCESSFUL] == 1 &&
              by[STORE_FAILED] == 1 && pending == 1);
  ASSERT_EQ_INT(store_dismiss(s, ID_C, 2104), 0);
  ASSERT_EQ_INT(store_dismiss(s, ID_C, 2105), STORE_NONE);
  ASSERT_EQ_INT(store_dismiss(s, "0123456789abcdef0123456789abcdef", 2105),
                STORE_NONE);
  ASSERT_EQ_INT(store_result(s, ID_C, 0, &body, &len), STORE_NONE);
  ASSERT_EQ_INT(store_body(s, ID_C, &body, &len), STORE_NONE);
  ASSERT_EQ_INT(store_renew(s, "r2", ID_C, 1, 3000), STORE_NONE);
  ASSERT_EQ_INT(store_complete(s, "r2", ID_C, 1, "x", 1, 2106), STORE_NONE);
  store_get(s, ID_C, &g);
  ASSERT_EQ_INT(g.status, STORE_DISMISSED);
  ASSERT_NEAR(g.finished, 2104, 0);
  ASSERT_EQ_INT(store_counts(s, by, &pending), 0);
  ASSERT_TRUE(by[STORE_DISMISSED] == 1 && by[STORE_RUNNING] == 0 &&
              pending == 0);

  /* expire: finished before 2101 (A at 2019.5, B at 2100), not C */
  long n = 0;
  ASSERT_EQ_INT(store_expire(s, 2101, &n), 0);
  ASSERT_EQ_INT(n, 2);
  ASSERT_EQ_INT(store_get(s, ID_A, &g), STORE_NONE);
  ASSERT_EQ_INT(store_result(s, ID_A, 0, &body, &len), STORE_NONE);
  ASSERT_EQ_INT(store_get(s, ID_C, &g), 0);
  ASSERT_EQ_INT(store_expire(s, 1e12, &n), 0);
  ASSERT_EQ_INT(n, 1);
}

/* Four claimers on two handles, one job of many chunks: each chunk once. */
#define RACE_CHUNKS 400
static const char *RACE_ID = "dddddddddddddddddddddddddddddd44";
static atomic_int claimed[RACE_CHUNKS];
static atomic_int errors;
/* Each claimer waits here after its first chunk, so every one of the four
 * computes at least one whatever the scheduler does: the handles
 * interleave by construction, not by luck. */
static pthread_barrier_t first_claimed;

typedef struct claimer {
  store *s;
  char owner[16];
} claimer;

static void *claim_all(void *arg) {
  claimer *c = arg;
  char id[STORE_ID_LEN + 1];
  long k;
  int rc, first = 1;
  while ((rc = store_claim(c->s, c->owner, 5000, 600, id, &k)) == 0) {
    if (first) {
      pthread_barrier_wait(&first_claimed);
      first = 0;
    }
    if (k < 0 || k >= RACE_CHUNKS || strcmp(id, RACE_ID))
      atomic_fetch_add(&errors, 1);
    else
      atomic_fetch_add(&claimed[k], 1);
    if (store_complete(c->s, c->owner, id, k, c->owner, strlen(c->owner),
                       5001) != 0)
      atomic_fetch_add(&errors, 1);
  }
  if (rc != STORE_NONE) {
    fprintf(stderr, "claim: %s\n", store_error(c->s));
    atomic_fetch_add(&errors, 1);
  }
  if (first) /* claimed nothing: a failure above; do not leave the rest */
    pthread_barrier_wait(&first_claimed);
  return NULL;
}

static void test_race(store *s1) {
  store *s2 = open_store();
  store_chunk *ch = calloc(RACE_CHUNKS, sizeof *ch);
  for (int i = 0; i < RACE_CHUNKS; i++)
    ch[i].items = 1;
  store_job j;
  make_job(&j, RACE_ID, "/batch", 4000);
  ASSERT_EQ_INT(store_submit(s1, &j, "{}", 2, ch, RACE_CHUNKS), 0);
  free(ch);
  claimer c[4] = {{s1, "p1"}, {s1, "p2"}, {s2, "q1"}, {s2, "q2"}};
  pthread_t t[4];
  pthread_barrier_init(&first_claimed, NULL, 4);
  for (int i = 0; i < 4; i++)
    pthread_create(&t[i], NULL, claim_all, &c[i]);
  for (int i = 0; i < 4; i++)
    pthread_join(t[i], NULL);
  pthread_barrier_destroy(&first_claimed);
  int once = 0;
  for (int i = 0; i < RACE_CHUNKS; i++)
    once += atomic_load(&claimed[i]) == 1;
  ASSERT_EQ_INT(once, RACE_CHUNKS);
  ASSERT_EQ_INT(atomic_load(&errors), 0);
  store_job g;
  store_get(s2, RACE_ID, &g);
  ASSERT_EQ_INT(g.status, STORE_SUCCESSFUL);
  ASSERT_TRUE(g.chunks_done == RACE_CHUNKS && g.items_done == RACE_CHUNKS);
  /* both handles computed some: each claimer's first chunk (the barrier)
   * at least */
  int by_q = 0;
  for (int k = 0; k < RACE_CHUNKS; k++) {
    char *buf;
    size_t len;
    if (store_result(s1, RACE_ID, k, &buf, &len) == 0) {
      by_q += buf[0] == 'q';
      free(buf);
    }
  }
  printf("race: %d of %d chunks by the second handle\n", by_q, RACE_CHUNKS);
  ASSERT_TRUE(by_q >= 2 && by_q <= RACE_CHUNKS - 2);
  store_close(s2);
}

/* A job of one chunk with a body of @a len bytes: store_submit's code. */
static int submit_one(store *s, const char *id, size_t len) {
  char *body = calloc(1, len + 1);
  store_chunk c[1] = {{0, 1}};
  store_job j;
  make_job(&j, id, "/orbit", 6000);
  for (size_t i = 0; i < len; i++)
    body[i] = (char)('a' + rand() % 26); /* not compressible to nothing */
  int rc = store_submit(s, &j, body, len, c, 1);
  free(body);
  return rc;
}

/* The directory @a dir made read-only for this process: as another user
 * than root, its file's mode; as root, which permissions do not stop, a
 * read-only bind mount of the directory on itself in a mount namespace of
 * this (forked) process alone.  0, or 77 when neither can be done. */
static int make_read_only(const char *dir, const char *file) {
  if (geteuid() != 0)
    return chmod(file, 0444) == 0 && chmod(dir, 0555) == 0 ? 0 : 77;
  if (unshare(CLONE_NEWNS) != 0 ||
      mount(NULL, "/", NULL, MS_REC | MS_PRIVATE, NULL) != 0 ||
      mount(dir, dir, NULL, MS_BIND, NULL) != 0 ||
      mount(NULL, dir, NULL, MS_REMOUNT | MS_BIND | MS_RDONLY, NULL) != 0) {
    printf("read-only: no mount namespace (%s)\n", strerror(errno));
    return 77;
  }
  return 0;
}

/* In a child process: a store opened writable whose directory is then
 * made read-only fails its writes and still reads; a store opened on the
 * read-only directory is opened read-only, the same.  The child's exit
 * code: its failures, or 77 when it could not make the directory
 * read-only. */
static int read_only_child(const char *dir, const char *file) {
  test_failures_ = 0; /* the parent's, inherited by fork: not this child's */
  char u[1300];
  snprintf(u, sizeof u, "sqlite:%s", file);
  store *s = NULL, *r = NULL;
  char why[512], id[STORE_ID_LEN + 1];
  long k;
  store_job g;
  ASSERT_EQ_INT(store_open(u, &s, why, sizeof why), 0);
  ASSERT_EQ_INT(submit_one(s, "ffffffffffffffffffffffffffffff01", 10), 0);
  int rc = make_read_only(dir, file);
  if (rc) {
    store_close(s);
    return rc;
  }
  /* EVIDENCE: issue 30 §3, a read-only store fails new jobs */
  ASSERT_EQ_INT(submit_one(s, "ffffffffffffffffffffffffffffff02", 10),
                STORE_ERROR);
  printf("made read-only: %s\n", store_error(s));
  ASSERT_TRUE(strstr(store_error(s), "read-only") != NULL);
  ASSERT_EQ_INT(store_claim(s, "r", 6002, 10, id, &k), STORE_ERROR);
  ASSERT_EQ_INT(store_get(s, "ffffffffffffffffffffffffffffff01", &g), 0);
  store_close(s);
  ASSERT_EQ_INT(store_open(u, &r, why, sizeof why), 0);
  if (r) {
    ASSERT_EQ_INT(store_get(r, "ffffffffffffffffffffffffffffff01", &g), 0);
    ASSERT_EQ_INT(submit_one(r, "ffffffffffffffffffffffffffffff03", 10),
                  STORE_ERROR);
    printf("opened read-only: %s\n", store_error(r));
    store_close(r);
  }
  return test_failures_ ? 1 : 0;
}

/* A store made read-only under it (read_only_child), or, where this
 * process cannot do that, opened with ?mode=ro. */
static void test_read_only(const char *path) {
  char dir[1100], file[1200];
  snprintf(dir, sizeof dir, "%s.ro", path);
  snprintf(file, sizeof file, "%s/store.sqlite", dir);
  pid_t pid = fork();
  if (pid == 0) {
    int rc = read_only_child(dir, file);
    fflush(stdout);
    _exit(rc);
  }
  int st = 0;
  waitpid(pid, &st, 0);
  int code = WIFEXITED(st) ? WEXITSTATUS(st) : 1;
  chmod(dir, 0755);
  char cmd[1300];
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
  ASSERT_EQ_INT(system(cmd), 0);
  if (code != 77) {
    ASSERT_EQ_INT(code, 0);
    return;
  }
  char ro[1200];
  snprintf(ro, sizeof ro, "%s?mode=ro", uri);
  store *r = NULL;
  char why[512];
  ASSERT_EQ_INT(store_open(ro, &r, why, sizeof why), 0);
  if (r) {
    store_job g;
    ASSERT_EQ_INT(store_get(r, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeeee5", &g), 0);
    ASSERT_EQ_INT(submit_one(r, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeeee6", 10),
                  STORE_ERROR);
    printf("?mode=ro: %s\n", store_error(r));
    store_close(r);
  }
}

/* A full disk, as a file size limit (RLIMIT_FSIZE, which root obeys too):
 * the write that does not fit fails, the store is intact and takes the
 * next write once there is room. */
static void test_full(void) {
  store *s = open_store();
  struct rlimit old, low = {256 * 1024, 0};
  getrlimit(RLIMIT_FSIZE, &old);
  low.rlim_max = old.rlim_max;
  signal(SIGXFSZ, SIG_IGN);
  ASSERT_EQ_INT(setrlimit(RLIMIT_FSIZE, &low), 0);
  ASSERT_EQ_INT(submit_one(s, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeee10", 1 << 20),
                STORE_ERROR);
  printf("full: %s\n", store_error(s));
  setrlimit(RLIMIT_FSIZE, &old);
  store_job g;
  ASSERT_EQ_INT(store_get(s, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeee10", &g),
                STORE_NONE);
  ASSERT_EQ_INT(submit_one(s, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeee11", 1 << 20), 0);
  store_close(s);
}

/* SQLite: the file deleted or replaced under the store, read-only, full;
 * its directories made when missing. */
static void test_sqlite_faults(const char *path) {
  store *s = open_store();
  ASSERT_EQ_INT(submit_one(s, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeeee5", 2), 0);
  store_close(s);
  test_read_only(path);
  test_full();

  /* EVIDENCE: issue 30 §3, a store whose file was deleted fails new jobs */
  s = open_store();
  ASSERT_EQ_INT(unlink(path), 0);
  ASSERT_EQ_INT(submit_one(s, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeeee7", 2),
                STORE_ERROR);
  printf("deleted: %s\n", store_error(s));
  ASSERT_TRUE(strstr(store_error(s), "deleted") != NULL);
  store_job g;
  ASSERT_EQ_INT(store_get(s, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeeee5", &g),
                STORE_ERROR);
  store_close(s);
  /* replaced: another file at the path */
  s = open_store();
  char moved[1100];
  snprintf(moved, sizeof moved, "%s.moved", path);
  ASSERT_EQ_INT(rename(path, moved), 0);
  store *t = open_store();
  store_close(t);
  ASSERT_EQ_INT(submit_one(s, "eeeeeeeeeeeeeeeeeeeeeeeeeeeeeee8", 2),
                STORE_ERROR);
  ASSERT_TRUE(strstr(store_error(s), "replaced") != NULL);
  store_close(s);
  unlink(moved);

  /* directories made when missing */
  char deep[1200], cmd[1300];
  snprintf(deep, sizeof deep, "sqlite:%s.d/a/b/store.sqlite", path);
  store *r = NULL;
  char why[512];
  ASSERT_EQ_INT(store_open(deep, &r, why, sizeof why), 0);
  store_close(r);
  snprintf(cmd, sizeof cmd, "rm -rf '%s.d'", path);
  ASSERT_EQ_INT(system(cmd), 0);

  /* neither a store URI nor a reachable database */
  ASSERT_EQ_INT(store_open("mysql://x", &r, why, sizeof why), STORE_ERROR);
  ASSERT_TRUE(r == NULL && strstr(why, "sqlite:") != NULL);
  ASSERT_EQ_INT(
      store_open("sqlite:/proc/no/such/dir/x.sqlite", &r, why, sizeof why),
      STORE_ERROR);
  ASSERT_EQ_INT(store_open("postgresql://127.0.0.1:1/none?connect_timeout=2",
                           &r, why, sizeof why),
                STORE_ERROR);
  printf("unreachable: %s\n", why);
}

/* PostgreSQL: a database of this test's own in the cluster at @a base
 * (created, or dropped when @a create is 0), so that other tests on the
 * same cluster (the fixture pg) keep their tables; its URI into uri_buf.
 * 0, or 1 with the reason printed. */
static int pg_database(const char *base, int create) {
  char name[64], sql[128];
  snprintf(name, sizeof name, "ss_store_test_%ld", (long)getpid());
  PGconn *c = PQconnectdb(base);
  snprintf(sql, sizeof sql,
           create ? "CREATE DATABASE %s" : "DROP DATABASE %s WITH (FORCE)",
           name);
  PGresult *r = PQstatus(c) == CONNECTION_OK ? PQexec(c, sql) : NULL;
  int rc = PQresultStatus(r) == PGRES_COMMAND_OK ? 0 : 1;
  if (rc)
    fprintf(stderr, "%s: %s", sql, PQerrorMessage(c));
  PQclear(r);
  PQfinish(c);
  /* postgresql://user@host:port/DB?params: DB replaced, or added */
  const char *host = strstr(base, "://"), *q = strchr(base, '?');
  host = host ? host + 3 : base;
  const char *slash = strchr(host, '/');
  size_t head = slash && (!q || slash < q)
                    ? (size_t)(slash - base)
                    : (size_t)((q ? q : base + strlen(base)) - base);
  snprintf(uri_buf, sizeof uri_buf, "%.*s/%s%s", (int)head, base, name,
           q ? q : "");
  return rc;
}

/* PostgreSQL: a connection broken under the store (its backend ended, as
 * by a server restart) fails the call that finds it, and the next call
 * connects again. */
static void test_pg_broken(store *s) {
  store_job g;
  ASSERT_EQ_INT(store_get(s, RACE_ID, &g), 0);
  PGconn *c = PQconnectdb(uri);
  PGresult *r = PQexec(c, "SELECT pg_terminate_backend(pid) FROM "
                          "pg_stat_activity WHERE datname = current_database() "
                          "AND pid <> pg_backend_pid()");
  ASSERT_TRUE(PQresultStatus(r) == PGRES_TUPLES_OK && PQntuples(r) >= 1);
  PQclear(r);
  PQfinish(c);
  /* EVIDENCE: issue 30 §3, an unreachable store fails new jobs */
  ASSERT_EQ_INT(store_get(s, RACE_ID, &g), STORE_ERROR);
  printf("broken: %s\n", store_error(s));
  ASSERT_EQ_INT(store_get(s, RACE_ID, &g), 0);
}

int main(int argc, char **argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: test_store sqlite:PATH | postgresql://... | "
                    "@FILE\n");
    return 2;
  }
  uri = argv[1];
  if (uri[0] == '@') {
    FILE *f = fopen(uri + 1, "r");
    if (!f || !fgets(uri_buf, sizeof uri_buf, f)) {
      if (f)
        fclose(f);
      if (getenv("SS_REQUIRE_PG")) {
        fprintf(stderr, "no PostgreSQL: %s unreadable\n", uri + 1);
        return 1;
      }
      printf("no PostgreSQL (%s unreadable): skipped\n", uri + 1);
      return 77;
    }
    fclose(f);
    uri_buf[strcspn(uri_buf, "\n")] = 0;
    uri = uri_buf;
  }
  int lite = !strncmp(uri, "sqlite:", 7);
  char base[sizeof uri_buf];
  snprintf(base, sizeof base, "%s", uri);
  if (lite)
    unlink(uri + 7);
  else if (pg_database(base, 1))
    return 1;
  else
    uri = uri_buf;
  srand(7);
  store *s = open_store();
  printf("store: %s\n", store_kind(s));
  test_jobs(s);
  test_claims(s);
  test_fail_dismiss(s);
  test_race(s);
  if (!lite)
    test_pg_broken(s);
  store_close(s);
  if (lite)
    test_sqlite_faults(uri + 7);
  else
    ASSERT_EQ_INT(pg_database(base, 0), 0);
  TEST_DONE();
}
