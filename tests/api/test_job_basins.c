/*
 * test_job_basins.c: a /basins served as a job, its chunks run in shuffled
 * orders within their stage, answers what the synchronous /basins answers,
 * byte for byte.
 *
 * The slices: the paper's set over 7 rows of 2730 cells (groups of 3 rows:
 * 3, 3 and 1), the set of issue 32 over 3 rows of 4097 cells (groups of a
 * row; max_period 8, cells that land on no attractor the search names) and
 * over 32x32 cells, a set with a slow attractor and cells left unresolved
 * (16x16 cells, one group), and a set where stage 2 finds an attractor by
 * Newton on the return map (8x8 cells, one group); on one thread and on
 * two.  The cut: stage 0
 * the attractors, stage 1 the groups of rows (their cells the items), stage
 * 2 the answer, the only visible chunk.  The last chunks read what is
 * stored: attractors of another build, or labels of other rows, fail the
 * job rather than answer another map.
 * Usage: test_job_basins
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "job_runner.h"
#include "stickslip_api.h"
#include "test.h"

#define PAPER "{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1}"
#define ISSUE32                                                                \
  "{\"chi\":0.6673,\"eta\":2.5843,\"us\":0.1883,\"ur\":2.4124,\"V\":1}"
#define SIMULATION                                                             \
  "{\"chi\":0.4977,\"eta\":0.3593,\"us\":0.1201,\"ur\":0.8447,\"V\":1}"
#define NEWTON                                                                 \
  "{\"chi\":0.54,\"eta\":4.8436,\"us\":0.0574,\"ur\":0.3402,\"V\":1}"

typedef struct slice {
  const char *body;
  long cells;
  size_t groups;
  int from_simulation; /* its answer names an attractor found so */
} slice;

static const slice SLICES[] = {
    {"{\"params\":" PAPER
     ",\"axes\":[{\"variable\":\"x1\",\"from\":-2,\"to\":4,"
     "\"n\":7},{\"variable\":\"x2\",\"from\":0,\"to\":8,\"n\":2730}],"
     "\"state\":{\"v1\":0,\"v2\":1}}",
     7 * 2730, 3, 0},
    {"{\"params\":" ISSUE32 ",\"axes\":[{\"variable\":\"x1\","
     "\"from\":-3.4340246468289752,\"to\":4.565975353171025,\"n\":3},"
     "{\"variable\":\"x2\",\"from\":-5.151842719659786,"
     "\"to\":6.848157280340214,\"n\":4097}],\"state\":{\"v1\":0,\"v2\":1},"
     "\"max_period\":8}",
     3 * 4097, 3, 0},
    {"{\"params\":" ISSUE32 ",\"axes\":[{\"variable\":\"x1\","
     "\"from\":-3.4340246468289752,\"to\":4.565975353171025,\"n\":32},"
     "{\"variable\":\"x2\",\"from\":-5.151842719659786,"
     "\"to\":6.848157280340214,\"n\":32}],\"state\":{\"v1\":0,\"v2\":1},"
     "\"max_period\":8}",
     32 * 32, 1, 0},
    {"{\"params\":" SIMULATION ",\"axes\":[{\"variable\":\"x1\","
     "\"from\":-1.456,\"to\":1.456,\"n\":16},{\"variable\":\"x2\","
     "\"from\":-1.456,\"to\":2.912,\"n\":16}],\"state\":{\"v1\":0,\"v2\":1}}",
     16 * 16, 1, 0},
    {"{\"params\":" NEWTON ",\"axes\":[{\"variable\":\"x1\","
     "\"from\":-1.875,\"to\":2.125,\"n\":8},{\"variable\":\"x2\","
     "\"from\":-1.77,\"to\":2.23,\"n\":8}],\"state\":{\"v1\":0,\"v2\":1}}",
     8 * 8, 1, 1},
};

static size_t basins_endpoint(void) {
  size_t ep = api_endpoint_count();
  ASSERT_EQ_INT(api_route("POST", "/basins", &ep), 200);
  return ep;
}

/* EVIDENCE: stickslip_api.h "Jobs": a /basins' rows of cells are cut in
 * groups, and the job's answer is byte for byte the synchronous one */
static void check_slice(const slice *sl, unsigned threads) {
  size_t ep = basins_endpoint(), len = strlen(sl->body);
  api_limits lim;
  api_limits_default(&lim);
  lim.map_threads = threads;
  api_response s;
  api_handle(ep, sl->body, len, &lim, NULL, &s);
  ASSERT_EQ_INT(s.status, 200);
  ASSERT_EQ_INT(strstr(s.body, "\"found_by\":\"simulation\"") != NULL,
                sl->from_simulation);
  static const job_order ORDERS[] = {JOB_SHUFFLE, JOB_SHUFFLE, JOB_REVERSE};
  for (size_t i = 0; i < sizeof ORDERS / sizeof ORDERS[0]; i++) {
    api_response r;
    job_trace t;
    job_answer(ep, sl->body, len, &lim, ORDERS[i], 11u * (unsigned)i + 3, &r,
               &t);
    test_checks_++;
    if (r.status != 200 || r.len != s.len || memcmp(r.body, s.body, s.len))
      TEST_FAIL_("order %d: the job answers %d\n%.1500s\nthe request "
                 "answers\n%.1500s",
                 (int)ORDERS[i], r.status, r.body ? r.body : "", s.body);
    ASSERT_EQ_INT(t.stages, 3);
    ASSERT_EQ_INT((long)t.chunks, (long)sl->groups + 2);
    ASSERT_EQ_INT(t.bad_reads, 0);
    ASSERT_EQ_INT(t.items, sl->cells);
    ASSERT_EQ_INT(t.items_sum, sl->cells);
    ASSERT_TRUE(t.content_type && !strcmp(t.content_type, "application/json"));
    api_response_free(&r);
  }
  printf("%.60s... on %u thread(s): %zu groups, the same %zu bytes in three "
         "orders\n",
         sl->body, threads, sl->groups, s.len);
  api_response_free(&s);
}

/* The results of a job's chunks, kept in memory. */
typedef struct kept {
  char *res[8];
  size_t len[8];
} kept;

static int kept_read(void *cls, size_t k, char **buf, size_t *len) {
  kept *s = cls;
  if (k >= 8 || !s->res[k] || !(*buf = malloc(s->len[k] + 1)))
    return -1;
  memcpy(*buf, s->res[k], s->len[k] + 1);
  *len = s->len[k];
  return 0;
}

/* Chunk @a k of @a j run with what @a s keeps: its status; its result
 * kept when 200. */
static int run_kept(api_job *j, size_t k, kept *s, const api_limits *lim) {
  api_job_inputs in = {kept_read, s, 0};
  api_response r;
  int status = api_job_run(j, k, &in, lim, NULL, &r);
  if (status == 200) {
    free(s->res[k]);
    s->res[k] = malloc(r.len + 1);
    memcpy(s->res[k], r.body, r.len);
    s->res[k][r.len] = 0;
    s->len[k] = r.len;
  }
  api_response_free(&r);
  return status;
}

/* Replace the first @a from in chunk @a k's result by @a to (as long). */
static void tamper(kept *s, size_t k, const char *from, const char *to) {
  char *p = strstr(s->res[k], from);
  ASSERT_TRUE(p != NULL && strlen(from) == strlen(to));
  if (p)
    memcpy(p, to, strlen(to));
}

/* EVIDENCE: the last chunks take the stored attractors and labels, and
 * refuse what is not theirs */
static void check_reads(void) {
  const slice *sl = &SLICES[0];
  size_t ep = basins_endpoint();
  api_limits lim;
  api_limits_default(&lim);
  api_job *j;
  api_response r;
  kept s;
  memset(&s, 0, sizeof s);
  ASSERT_EQ_INT(api_job_open(ep, sl->body, strlen(sl->body), &lim, &j, &r), 0);
  ASSERT_EQ_INT(api_job_chunks(j), 5);
  ASSERT_TRUE(!api_job_visible(j, 0) && !api_job_visible(j, 3) &&
              api_job_visible(j, 4));
  ASSERT_EQ_INT(api_job_chunk_items(j, 1), 3 * 2730);
  ASSERT_EQ_INT(api_job_chunk_items(j, 3), 2730);
  ASSERT_EQ_INT(api_job_chunk_items(j, 4), 0);
  for (size_t k = 0; k < 5; k++)
    ASSERT_EQ_INT(run_kept(j, k, &s, &lim), 200);
  ASSERT_TRUE(strstr(s.res[4], "\"attractors\":[{\"label\":0") != NULL);
  /* labels of other rows */
  tamper(&s, 2, "\"row\":3", "\"row\":0");
  ASSERT_EQ_INT(run_kept(j, 4, &s, &lim), 500);
  tamper(&s, 2, "\"row\":0", "\"row\":3");
  ASSERT_EQ_INT(run_kept(j, 4, &s, &lim), 200);
  /* labels cut short */
  char *lab = strstr(s.res[3], "\"labels\":\"");
  ASSERT_TRUE(lab != NULL);
  if (lab) {
    lab += 10;
    memmove(lab, lab + 4, strlen(lab + 4) + 1);
    s.len[3] -= 4;
  }
  ASSERT_EQ_INT(run_kept(j, 4, &s, &lim), 500);
  ASSERT_EQ_INT(run_kept(j, 3, &s, &lim), 200);
  /* attractors of another build: another version, another size */
  char *version = strstr(s.res[0], "\"version\":\"");
  ASSERT_TRUE(version != NULL);
  if (version)
    version[11] = 'x';
  ASSERT_EQ_INT(run_kept(j, 1, &s, &lim), 500);
  ASSERT_EQ_INT(run_kept(j, 4, &s, &lim), 500);
  ASSERT_EQ_INT(run_kept(j, 0, &s, &lim), 200);
  char *size = strstr(s.res[0], "\"size\":");
  ASSERT_TRUE(size != NULL);
  if (size)
    size[7] = size[7] == '9' ? '8' : '9';
  ASSERT_EQ_INT(run_kept(j, 1, &s, &lim), 500);
  ASSERT_EQ_INT(run_kept(j, 0, &s, &lim), 200);
  ASSERT_EQ_INT(run_kept(j, 4, &s, &lim), 200);
  /* a stage the store cannot give */
  free(s.res[2]);
  s.res[2] = NULL;
  ASSERT_EQ_INT(run_kept(j, 4, &s, &lim), 503);
  for (size_t k = 0; k < 8; k++)
    free(s.res[k]);
  api_job_free(j);
}

int main(void) {
  gsl_set_error_handler_off();
  check_reads();
  for (size_t i = 0; i < sizeof SLICES / sizeof SLICES[0]; i++)
    for (unsigned threads = 1; threads <= 2; threads++)
      check_slice(&SLICES[i], threads);
  TEST_DONE();
}
