/*
 * test_http_limits.c (CTest http_limits): each per-request limit set by its
 * flag and answered as a problem that names it, and the compute time limit
 * --max-seconds.
 */
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "fixture.h"

/* EVIDENCE: docs/howto/limits.md: each per-request limit has its flag;
 * README "Errors": a limit that stops a request is a 422 limit-exceeded whose
 * limit and limit_value name it, a body over --max-body a 413, nesting
 * deeper than the limit a 400 invalid-json.  That a search over --max-orbits
 * answers 200 with the first orbits and counts the rest in
 * search.truncated is stated nowhere in README. */
static void test_flag_limits(void) {
  daemon_proc d;
  const char *args[] = {"--max-events",
                        "50",
                        "--max-orbits",
                        "1",
                        "--max-depth",
                        "4",
                        "--max-body",
                        "1000",
                        "--max-samples",
                        "10",
                        "--max-horizon",
                        "1e9",
                        "--max-points",
                        "10",
                        NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;
  struct {
    const char *name, *path, *body, *limit;
    double limit_value;
    const char *pointer;
  } cases[] = {
      {"max-events", "/simulate",
       "{" PAPER ",\"initial\":" X0 ",\"t_end\":1000,\"events\":false}",
       "max_events", 50, "/t_end"},
      {"max-samples", "/simulate",
       "{" PAPER ",\"initial\":" X0 ",\"t_end\":10,\"samples\":{\"n\":11}}",
       "max_samples", 10, "/samples/n"},
      {"max-points", "/continue",
       "{" PAPER ",\"guess\":{\"durations\":[4.4975,2.7227,3.0513]},"
       "\"parameter\":\"ur\",\"range\":[0.3,1.5],\"max_points\":11}",
       "max_points", 10, "/max_points"},
  };
  for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
    json_t *j = expect_problem(cases[i].name, "POST", cases[i].path, JSON,
                               cases[i].body, 422, "/problems/limit-exceeded",
                               cases[i].pointer);
    const char *l = json_string_value(json_object_get(j, "limit"));
    ASSERT_TRUE(l && strcmp(l, cases[i].limit) == 0);
    ASSERT_NEAR(num(j, "/limit_value"), cases[i].limit_value, 0);
    json_decref(j);
  }
  /* stop_after under --max-events: the run stops at its 40th event, inside
   * the limit, over a horizon that would need some 2.6e8 */
  {
    json_t *j = post("/simulate",
                     "{" PAPER ",\"initial\":" X0 ",\"t_end\":9e8,"
                     "\"events\":false,\"stop_after\":40}",
                     200);
    ASSERT_EQ_INT((int)num(j, "/n_events"), 40);
    json_decref(j);
  }
  /* max-depth 4: five levels are refused (under the default of 32 this body
   * would reach the decoder and get 422 unknown-field /a) */
  {
    json_t *j =
        expect_problem("max-depth", "POST", "/orbit", JSON, "{\"a\":[[[[1]]]]}",
                       400, "/problems/invalid-json", NULL);
    const char *detail = json_string_value(json_object_get(j, "detail"));
    ASSERT_TRUE(detail && strstr(detail, "deeper than 4 levels"));
    json_decref(j);
  }
  /* max-orbits 1: the search over all kinds finds 4 orbits for the paper's
   * data without the limit (the overshoot orbit, two stick-slip orbits and
   * a period-3 orbit; about 10 ms); one is returned and the 3 others are
   * counted in search.truncated (with their repeats, 8 here) */
  {
    json_t *j =
        post("/orbit",
             "{" PAPER ",\"kind\":\"all\",\"finite_difference\":false}", 200);
    ASSERT_EQ_INT(json_array_size(json_object_get(j, "orbits")), 1);
    ASSERT_TRUE(num(j, "/search/truncated") >= 3);
    json_decref(j);
  }
  /* max-body: 413 from Content-Length */
  {
    char body[2001];
    memset(body, ' ', 2000);
    body[0] = '{';
    body[1999] = '}';
    body[2000] = 0;
    json_t *j = expect_problem("max-body flag", "POST", "/orbit", JSON, body,
                               413, "/problems/limit-exceeded", NULL);
    const char *l = json_string_value(json_object_get(j, "limit"));
    ASSERT_TRUE(l && strcmp(l, "max_body") == 0);
    ASSERT_NEAR(num(j, "/limit_value"), 1000, 0);
    json_decref(j);
  }
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

/* EVIDENCE: docs/howto/limits.md: --max-seconds bounds the compute time of a
 * request, and /simulate stops when it runs out; README "Errors": a 422
 * limit-exceeded that names max_seconds */
static void test_time_limit(void) {
  daemon_proc d;
  const char *args[] = {
      "--max-seconds", "0.05", "--max-events", "1000000000", "--max-horizon",
      "1e9",           NULL};
  ASSERT_EQ_INT(daemon_start(BIN, args, &d), 0);
  PORT = d.port;
  /* about 2.6e8 events: 172 s without the limit on a 2-core test machine
   * (release build), some 3000 times the budget, so over 0.05 s on any
   * machine.  The answer names the flag's value and comes when that budget
   * runs out: the default budget (10 s) would also end this run with a
   * max_seconds 422, but later */
  double t0 = mono();
  http_resp r;
  ASSERT_EQ_INT(http_do(PORT, "POST", "/simulate", "application/json",
                        "{" PAPER ",\"initial\":" X0 ",\"t_end\":9e8,"
                        "\"events\":false}",
                        &r),
                0);
  double dt = mono() - t0;
  json_t *j = problem_body("max-seconds 0.05", &r, 422,
                           "/problems/limit-exceeded", NULL);
  const char *l = json_string_value(json_object_get(j, "limit"));
  ASSERT_TRUE(l && strcmp(l, "max_seconds") == 0);
  ASSERT_NEAR(num(j, "/limit_value"), 0.05, 1e-12);
  /* in its shortest digits, as every number the API writes (not jansson's
   * 0.050000000000000003) */
  ASSERT_TRUE(r.body && strstr(r.body, "\"limit_value\":0.05}") != NULL);
  printf("max-seconds 0.05: answered 422 after %.3f s\n", dt);
  ASSERT_TRUE(dt < 2);
  json_decref(j);
  http_free(&r);
  ASSERT_EQ_INT(daemon_stop(&d), 0);
  unlink(d.log_path);
}

int main(int argc, char **argv) {
  if (fixture_init(argc, argv))
    return 2;
  test_flag_limits();
  test_time_limit();
  TEST_DONE();
}
