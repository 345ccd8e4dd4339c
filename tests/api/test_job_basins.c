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
 * The NDJSON form (Accept: application/x-ndjson) of each slice: as a job,
 * the same bytes as the synchronous request, a chunk per line (the head,
 * each group, the last); its lines give the JSON form's labels exactly
 * (the rows' labels, then the relabelled runs of the last line) and its
 * last line has the JSON form's attractors and counts.
 * Usage: test_job_basins
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <jansson.h>

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

/* RFC 4648 base64 of @a s into @a out (room for its bytes): their number. */
static size_t unbase64(const char *s, unsigned char *out) {
  static const char T[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  size_t n = 0;
  unsigned v = 0;
  int bits = 0;
  for (; *s && *s != '='; s++) {
    const char *p = strchr(T, *s);
    v = v << 6 | (unsigned)(p ? p - T : 0);
    if ((bits += 6) >= 8)
      out[n++] = (unsigned char)(v >> (bits -= 8));
  }
  return n;
}

/* The labels of a /basins answer in the JSON form @a json, and as the
 * NDJSON form @a nd rebuilds them, must be the same bytes, and its last
 * line must have the JSON form's attractors and counts. */
static void check_lines(const char *json, const char *nd, long cells) {
  json_t *whole = json_loads(json, 0, NULL);
  const char *data = json_string_value(
      json_object_get(json_object_get(whole, "labels"), "data"));
  unsigned char *want = calloc((size_t)cells + 3, 1);
  unsigned char *got = calloc((size_t)cells + 3, 1);
  ASSERT_TRUE(data != NULL && want && got);
  ASSERT_EQ_INT((long)unbase64(data ? data : "", want), cells);
  long cols = 0, lines = 0;
  json_t *last = NULL;
  for (const char *p = nd; *p; p = strchr(p, '\n') + 1, lines++) {
    json_t *line = json_loadb(p, (size_t)(strchr(p, '\n') - p), 0, NULL);
    ASSERT_TRUE(line != NULL);
    json_t *lab = json_object_get(line, "labels");
    if (lines == 0) {
      cols = (long)json_integer_value(json_object_get(lab, "cols"));
      ASSERT_TRUE(json_array_size(json_object_get(line, "attractors")) > 0);
    } else if (json_is_string(lab)) {
      long row = (long)json_integer_value(json_object_get(line, "row"));
      ASSERT_TRUE(row * cols < cells);
      unbase64(json_string_value(lab), got + row * cols);
    } else {
      json_decref(last);
      last = json_incref(line);
    }
    json_decref(line);
  }
  ASSERT_TRUE(last && json_is_true(json_object_get(last, "done")));
  size_t i;
  json_t *run;
  json_array_foreach(json_object_get(last, "relabelled"), i, run) {
    long at = (long)json_integer_value(json_array_get(run, 0));
    long n = (long)json_integer_value(json_array_get(run, 1));
    ASSERT_TRUE(at >= 0 && n > 0 && at + n <= cells);
    if (at >= 0 && n > 0 && at + n <= cells)
      memset(got + at, (int)json_integer_value(json_array_get(run, 2)),
             (size_t)n);
  }
  test_checks_++;
  if (memcmp(got, want, (size_t)cells))
    TEST_FAIL_("the NDJSON form's labels are not the JSON form's%s", "");
  static const char *const SAME[] = {"attractors", "unresolved",
                                     "perpetual_slip", "returns", "input"};
  for (size_t k = 0; k < sizeof SAME / sizeof SAME[0]; k++)
    ASSERT_TRUE(json_equal(json_object_get(last, SAME[k]),
                           json_object_get(whole, SAME[k])));
  printf("  NDJSON: %ld lines, %zu relabelled runs\n", lines,
         json_array_size(json_object_get(last, "relabelled")));
  json_decref(last);
  json_decref(whole);
  free(want);
  free(got);
}

/* EVIDENCE: api/openapi.json /basins application/x-ndjson: a line per
 * chunk of the job, the job's answer the synchronous one byte for byte */
static void check_ndjson(const slice *sl, unsigned threads, const char *json) {
  size_t ep = basins_endpoint(), len = strlen(sl->body);
  api_limits lim;
  api_limits_default(&lim);
  lim.map_threads = threads;
  api_server_info srv;
  memset(&srv, 0, sizeof srv);
  srv.form = API_FORM_NDJSON;
  api_response s, r;
  api_handle(ep, sl->body, len, &lim, &srv, &s);
  ASSERT_EQ_INT(s.status, 200);
  ASSERT_TRUE(s.content_type &&
              !strcmp(s.content_type, "application/x-ndjson"));
  job_trace t;
  job_answer_form(ep, API_FORM_NDJSON, sl->body, len, &lim, JOB_SHUFFLE,
                  7u + threads, &r, &t);
  test_checks_++;
  if (r.status != 200 || r.len != s.len || memcmp(r.body, s.body, s.len))
    TEST_FAIL_("the NDJSON job answers %d\n%.1500s\nthe request "
               "answers\n%.1500s",
               r.status, r.body ? r.body : "", s.body);
  ASSERT_EQ_INT(t.stages, 3);
  ASSERT_EQ_INT((long)t.chunks, (long)sl->groups + 3);
  ASSERT_EQ_INT(t.bad_reads, 0);
  ASSERT_EQ_INT(t.items, sl->cells);
  ASSERT_TRUE(t.content_type &&
              !strcmp(t.content_type, "application/x-ndjson"));
  check_lines(json, s.body, sl->cells);
  api_response_free(&r);
  api_response_free(&s);
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
  check_ndjson(sl, threads, s.body);
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
