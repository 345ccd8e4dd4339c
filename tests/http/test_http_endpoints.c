/*
 * test_http_endpoints.c (CTest http_endpoints): every endpoint answers: /orbit
 * (with and without a guess, in physical units, an empty answer with its
 * reason), /stability and /simulate on the orbit /orbit returns, and /metrics
 * counting them.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixture.h"

static void test_endpoints(void) {
  http_resp r;
  ASSERT_EQ_INT(http_do(PORT, "GET", "/health", NULL, NULL, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(strstr(r.body, "\"ok\"") != NULL);
  http_free(&r);
  ASSERT_EQ_INT(http_do(PORT, "GET", "/version", NULL, NULL, &r), 0);
  ASSERT_TRUE(strstr(r.body, "\"version\":\"" SS_TEST_VERSION "\"") != NULL);
  http_free(&r);
  ASSERT_EQ_INT(http_do(PORT, "GET", "/openapi.json", NULL, NULL, &r), 0);
  json_t *spec = json_loads(r.body, 0, NULL);
  ASSERT_TRUE(spec && json_object_get(spec, "openapi"));
  json_decref(spec);
  http_free(&r);

  /* /orbit, no guess: the paper's orbit */
  json_t *o = post("/orbit", "{" PAPER ",\"kind\":\"overshoot\"}", 200);
  ASSERT_NEAR(num(o, "/orbits/0/phases/0/duration"), 4.4975, 1e-3);
  ASSERT_NEAR(num(o, "/orbits/0/stability/spectral_radius"), 0.19545, 1e-4);
  ASSERT_TRUE(num(o, "/orbits/0/stability/jacobian_difference") < 1e-6);
  /* reason explains only an absence; the closest rejection is in numbers */
  ASSERT_TRUE(json_object_get(o, "reason") == NULL);
  ASSERT_TRUE(num(o, "/rejected/violation/value") <= 0);
  json_t *none = post("/orbit",
                      "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,"
                      "\"ur\":0.4,\"V\":1},\"kind\":\"overshoot\"}",
                      200);
  ASSERT_EQ_INT(json_array_size(json_object_get(none, "orbits")), 0);
  ASSERT_TRUE(json_is_string(json_object_get(none, "reason")));
  ASSERT_NEAR(num(none, "/rejected/violation/value"), -0.110313724088, 1e-9);
  json_decref(none);
  /* /stability on the orbit as /orbit returned it */
  json_t *body = json_object();
  json_object_set_new(
      body, "params",
      json_deep_copy(json_object_get(json_object_get(o, "input"), "params")));
  json_object_set(body, "orbit",
                  json_array_get(json_object_get(o, "orbits"), 0));
  char *sb = json_dumps(body, JSON_COMPACT);
  json_t *s = post("/stability", sb, 200);
  ASSERT_NEAR(num(s, "/spectral_radius"),
              num(o, "/orbits/0/stability/spectral_radius"), 1e-12);
  ASSERT_TRUE(json_is_true(json_object_get(s, "feasible")));
  free(sb);
  /* /simulate from the orbit: one period returns to x0 */
  json_object_del(body, "orbit");
  json_object_set(body, "orbit",
                  json_array_get(json_object_get(o, "orbits"), 0));
  json_object_set_new(body, "t_end", json_real(num(o, "/orbits/0/period")));
  json_object_set_new(body, "events", json_false());
  sb = json_dumps(body, JSON_COMPACT);
  json_t *sim = post("/simulate", sb, 200);
  for (int i = 0; i < 3; i++) {
    char p1[32], p2[32];
    snprintf(p1, sizeof p1, "/final/x/%d", i);
    snprintf(p2, sizeof p2, "/orbits/0/x0/%d", i);
    ASSERT_NEAR(num(sim, p1), num(o, p2), 1e-12);
  }
  /* EVIDENCE: docs/api/simulate.md: a final-state request gets no events or
   * samples */
  ASSERT_TRUE(!json_object_get(sim, "events") &&
              !json_object_get(sim, "samples"));
  /* the third event, the return to the start, falls on t_end up to
   * rounding */
  ASSERT_TRUE(num(sim, "/n_events") >= 2 && num(sim, "/n_events") <= 3);
  free(sb);
  json_decref(sim);
  json_decref(s);
  json_decref(body);
  json_decref(o);

  /* with a guess */
  o = post("/orbit",
           "{" PAPER ",\"guess\":{\"durations\":[4.5,2.717,3.0536]},"
           "\"samples\":50}",
           200);
  ASSERT_NEAR(num(o, "/orbits/0/period"), 10.2714298553536, 1e-9);
  ASSERT_TRUE(
      json_array_size(json_object_get(
          json_object_get(json_array_get(json_object_get(o, "orbits"), 0),
                          "samples"),
          "t")) == 50);
  json_decref(o);
  /* physical units: omega = 2, so durations halve */
  o = post("/orbit",
           "{\"physical\":{\"m1\":2.5,\"m2\":0.625,\"k1\":8,\"k2\":2,"
           "\"Fs\":0.724,\"Fr\":6.178,\"v0\":2},\"kind\":\"overshoot\"}",
           200);
  ASSERT_NEAR(num(o, "/orbits/0/phases/0/duration"), 4.4974972908 / 2, 1e-8);
  ASSERT_NEAR(num(o, "/input/omega"), 2, 1e-15);
  json_decref(o);
  /* an empty answer with its reason */
  o = post("/orbit",
           "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.4,"
           "\"V\":1},\"kind\":\"overshoot\"}",
           200);
  ASSERT_EQ_INT(json_array_size(json_object_get(o, "orbits")), 0);
  ASSERT_TRUE(strstr(json_string_value(json_object_get(o, "reason")), "(3.2)"));
  json_decref(o);
  /* samples and events */
  sim = post("/simulate",
             "{" PAPER ",\"initial\":" X0 ",\"t_end\":20,"
             "\"samples\":{\"n\":11,\"from\":0,\"to\":20}}",
             200);
  ASSERT_EQ_INT(
      json_array_size(json_object_get(json_object_get(sim, "samples"), "x1")),
      11);
  ASSERT_TRUE(json_array_size(json_object_get(sim, "events")) > 0);
  json_decref(sim);
  /* metrics count what happened */
  ASSERT_EQ_INT(http_do(PORT, "GET", "/metrics", NULL, NULL, &r), 0);
  ASSERT_TRUE(strstr(r.body, "stickslip_requests_total{endpoint=\"orbit\","
                             "code=\"200\"} ") != NULL);
  ASSERT_TRUE(strstr(r.body, "stickslip_requests_in_flight") != NULL);
  ASSERT_TRUE(strstr(r.body, "stickslip_request_duration_seconds_bucket") !=
              NULL);
  http_free(&r);
}

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_endpoints();
  fixture_daemon_stop(&d);
  TEST_DONE();
}
