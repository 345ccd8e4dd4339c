/*
 * test_job_map.c: a /map served as a job, its chunks run in a shuffled
 * order within their stage, answers what the synchronous /map answers,
 * byte for byte but for the done line's "seconds".
 *
 * The maps: overshoot and stick-slip maps in two dimensions, every kind in
 * one dimension, a sweep in physical units, on one thread and on two; every
 * orbit field asked, so that every double the lattice's searches carry
 * from their chunks to the last one is written.  Each makes full searches
 * where families end, off its lattice, which the last chunk makes itself.
 * Usage: test_job_map
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>

#include "job_runner.h"
#include "stickslip_api.h"
#include "test.h"

static const char *const MAPS[] = {
    /* overshoot, 2-D: 9 lattice cells, 43 searches where families end */
    "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
    "\"axes\":[{\"parameter\":\"chi\",\"from\":0.04,\"to\":0.96,\"n\":16},"
    "{\"parameter\":\"ur\",\"from\":0.1086,\"to\":1.086,\"n\":16}],"
    "\"kind\":\"overshoot\",\"fields\":[\"kind\",\"n_turns\",\"period\","
    "\"durations\",\"stable\",\"spectral_radius\",\"min_margin\",\"modes\","
    "\"multipliers\",\"marginal\",\"found_by\"]}",
    /* stick-slip, 2-D: 16 lattice cells, 2 searches where families end */
    "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
    "\"axes\":[{\"parameter\":\"chi\",\"from\":0.1,\"to\":0.9,\"n\":12},"
    "{\"parameter\":\"eta\",\"from\":0.5,\"to\":10,\"n\":12}],"
    "\"kind\":\"stick-slip\",\"search_every\":4,\"fields\":[\"period\","
    "\"durations\",\"min_margin\",\"multipliers\",\"found_by\"]}",
    /* every kind, 1-D: 9 lattice cells, 6 searches where families end */
    "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,\"V\":1},"
    "\"axes\":[{\"parameter\":\"ur\",\"from\":0.1,\"to\":1.0,\"n\":60}],"
    "\"fields\":[\"kind\",\"period\",\"durations\",\"min_margin\","
    "\"multipliers\",\"found_by\",\"modes\"]}",
    /* physical units, 1-D */
    "{\"physical\":{\"m1\":1,\"m2\":0.25,\"k1\":0.8,\"k2\":0.2,\"Fs\":0.0724,"
    "\"Fr\":0.6178,\"v0\":1},\"axes\":[{\"parameter\":\"Fr\",\"from\":0.3,"
    "\"to\":1.0,\"n\":30}],\"search_every\":6}",
};

/* The seconds of the done line of @a body; -1 when it has none. */
static double done_seconds(const char *body) {
  const char *s = body ? strstr(body, "{\"done\":true") : NULL;
  s = s ? strstr(s, "\"seconds\":") : NULL;
  return s ? strtod(s + 10, NULL) : -1;
}

/* EVIDENCE: stickslip_api.h "Jobs": a /map's full searches of its lattice
 * are cut in groups, a last chunk spreads them and writes the answer, byte
 * for byte the synchronous one but for "seconds" */
static void check_map(const char *body, unsigned threads) {
  size_t ep = api_endpoint_count();
  ASSERT_EQ_INT(api_route("POST", "/map", &ep), 200);
  api_limits lim;
  api_limits_default(&lim);
  lim.map_threads = threads;
  /* what is compared is the answer, not its time: the default 10 s is
   * short for the maps' edge searches under the sanitizers on a loaded
   * machine (both answers then the same 422) */
  lim.max_seconds = 600;
  api_response s;
  api_handle(ep, body, strlen(body), &lim, NULL, &s);
  ASSERT_EQ_INT(s.status, 200);
  char *want = job_blank(s.body, s.len, "seconds");
  long cells = 0;
  for (const char *l = s.body; (l = strstr(l, "{\"index\":")); l++)
    cells++;
  static const job_order ORDERS[] = {JOB_SHUFFLE, JOB_SHUFFLE, JOB_REVERSE};
  for (size_t i = 0; i < sizeof ORDERS / sizeof ORDERS[0]; i++) {
    api_response r;
    job_trace t;
    job_answer(ep, body, strlen(body), &lim, ORDERS[i], 7u * (unsigned)i + 1,
               &r, &t);
    char *got = job_blank(r.body ? r.body : "", r.len, "seconds");
    test_checks_++;
    if (r.status != 200 || strcmp(got, want))
      TEST_FAIL_("order %d: the job answers %d\n%.2000s\nthe request "
                 "answers\n%.2000s",
                 (int)ORDERS[i], r.status, got, want);
    /* cut: groups of the lattice's searches, then the map */
    ASSERT_EQ_INT(t.stages, 2);
    ASSERT_TRUE(t.chunks >= 2);
    ASSERT_EQ_INT(t.bad_reads, 0);
    ASSERT_EQ_INT(t.items, cells);
    ASSERT_EQ_INT(t.items_sum, cells);
    ASSERT_TRUE(t.content_type &&
                !strcmp(t.content_type, "application/x-ndjson"));
    /* the compute time of every chunk, summed */
    ASSERT_TRUE(done_seconds(r.body) > 0);
    free(got);
    api_response_free(&r);
  }
  free(want);
  api_response_free(&s);
}

/* A map cut into many groups: search_every 1 searches every cell of a
 * 40-cell sweep in the groups, and none in the last chunk. */
static void check_many_groups(void) {
  const char *body =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"axes\":[{\"parameter\":\"ur\",\"from\":0.3,\"to\":1.0,"
      "\"n\":40}],\"search_every\":1,\"kind\":\"overshoot\"}";
  size_t ep = api_endpoint_count();
  ASSERT_EQ_INT(api_route("POST", "/map", &ep), 200);
  api_limits lim;
  api_limits_default(&lim);
  api_job *j;
  api_response r;
  ASSERT_EQ_INT(api_job_open(ep, body, strlen(body), &lim, &j, &r), 0);
  ASSERT_EQ_INT(api_job_chunks(j), 4); /* 16 + 16 + 8 searches, the map */
  ASSERT_EQ_INT(api_job_chunk_items(j, 0), 16);
  ASSERT_EQ_INT(api_job_chunk_items(j, 2), 8);
  ASSERT_EQ_INT(api_job_chunk_items(j, 3), 0);
  ASSERT_TRUE(!api_job_visible(j, 0) && api_job_visible(j, 3));
  ASSERT_EQ_INT(api_job_stage(j, 2), 0);
  ASSERT_EQ_INT(api_job_stage(j, 3), 1);
  /* the last chunk without its inputs fails, it does not search anew */
  ASSERT_EQ_INT(api_job_run(j, 3, NULL, &lim, NULL, &r), 500);
  api_response_free(&r);
  api_job_free(j);
  check_map(body, 1);
}

/* The stored results of a job's chunks, read by its later ones. */
typedef struct results {
  char *body[8];
  size_t len[8];
} results;

static int read_result(void *cls, size_t k, char **buf, size_t *len) {
  results *rs = cls;
  if (k >= 8 || !rs->body[k] || !(*buf = malloc(rs->len[k] + 1)))
    return -1;
  memcpy(*buf, rs->body[k], rs->len[k] + 1);
  *len = rs->len[k];
  return 0;
}

/* EVIDENCE: stickslip_api.h "Jobs": the last chunk of a /map makes the map
 * from the searches its groups stored, not anew: a period altered in a
 * stored search is the period the answer tells; and its seconds are those
 * of every chunk, summed */
static void check_taken(void) {
  const char *body =
      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
      "\"V\":1},\"axes\":[{\"parameter\":\"ur\",\"from\":0.3,\"to\":1.0,"
      "\"n\":40}],\"search_every\":1,\"kind\":\"overshoot\"}";
  size_t ep = api_endpoint_count();
  ASSERT_EQ_INT(api_route("POST", "/map", &ep), 200);
  api_limits lim;
  api_limits_default(&lim);
  api_job *j;
  api_response r;
  results rs;
  memset(&rs, 0, sizeof rs);
  ASSERT_EQ_INT(api_job_open(ep, body, strlen(body), &lim, &j, &r), 0);
  ASSERT_EQ_INT(api_job_chunks(j), 4);
  double sum = 0;
  int searched = 0; /* every cell of the sweep, each once, in the groups */
  for (size_t k = 0; k < 3; k++) {
    ASSERT_EQ_INT(api_job_run(j, k, NULL, &lim, NULL, &r), 200);
    rs.body[k] = r.body;
    rs.len[k] = r.len;
    const char *sec = strstr(r.body, "\"seconds\":");
    ASSERT_TRUE(sec != NULL);
    sum += sec ? strtod(sec + 10, NULL) : 0;
    for (const char *c = r.body; (c = strstr(c, "{\"cell\":")); c++)
      searched += atoi(c + 8) == searched;
  }
  ASSERT_EQ_INT(searched, 40);
  /* the last group (cells 32-39) has overshoot orbits: alter a period */
  char *p = strstr(rs.body[2], "\"period\":");
  ASSERT_TRUE(p != NULL);
  if (p) {
    char *end = strchr(p, ',');
    memcpy(p + 9, "1.5", 3);
    memset(p + 12, ' ', (size_t)(end - p - 12));
  }
  api_job_inputs in = {read_result, &rs};
  ASSERT_EQ_INT(api_job_run(j, 3, &in, &lim, NULL, &r), 200);
  ASSERT_TRUE(r.body && strstr(r.body, "\"period\":1.5,"));
  ASSERT_TRUE(done_seconds(r.body) >= sum && sum > 0);
  api_response_free(&r);
  for (size_t k = 0; k < 3; k++)
    free(rs.body[k]);
  api_job_free(j);
}

int main(void) {
  gsl_set_error_handler_off();
  for (size_t i = 0; i < sizeof MAPS / sizeof MAPS[0]; i++)
    check_map(MAPS[i], i % 2 ? 2u : 1u);
  check_many_groups();
  check_taken();
  TEST_DONE();
}
