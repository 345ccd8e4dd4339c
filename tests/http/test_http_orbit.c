/*
 * test_http_orbit.c (CTest http_orbit): /orbit against what else answers with
 * orbits: each cell of /map, and an orbit's samples placed for a curve.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "fixture.h"

/* EVIDENCE: docs/api/map.md: a complete cell holds what /orbit finds
 * for its parameters, the others at least what /orbit finds there too on
 * this sweep (continued from their neighbours); the last line counts the
 * cells, and fields selects the orbits' fields.  By default (@a lattice
 * NULL) every cell is complete and holds the very orbits /orbit returns,
 * to the last digit; with search_every 3 some are not. */
static void test_map_against_orbit(const char *lattice) {
  const char *P = "{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":%.17g,\"V\":1}";
  char body[512];
  snprintf(body, sizeof body,
           "{\"params\":{\"chi\":0.2,\"eta\":4,\"us\":0.0724,\"ur\":0.6178,"
           "\"V\":1},\"axes\":[{\"parameter\":\"ur\",\"from\":0.6,\"to\":0.9,"
           "\"n\":7}],\"kind\":\"overshoot\",%s"
           "\"fields\":[\"period\",\"modes\",\"found_by\"]}",
           lattice ? lattice : "");
  http_resp r;
  ASSERT_EQ_INT(http_do(PORT, "POST", "/map", JSON, body, &r), 0);
  ASSERT_EQ_INT(r.status, 200);
  ASSERT_TRUE(strstr(r.ctype, "application/x-ndjson") != NULL);
  int lines = 0, complete = 0, compared = 0;
  for (const char *t = r.body, *e; t && *t; t = e + 1) {
    if (!(e = strchr(t, '\n')))
      break;
    json_t *l = json_loadb(t, (size_t)(e - t), 0, NULL);
    ASSERT_TRUE(l != NULL);
    if (!l)
      break;
    if (json_is_true(json_object_get(l, "done"))) {
      ASSERT_EQ_INT(json_integer_value(json_object_get(l, "cells")), 7);
      ASSERT_EQ_INT(json_integer_value(json_object_get(l, "complete")),
                    complete);
      json_decref(l);
      lines++;
      continue;
    }
    lines++;
    double ur =
        json_number_value(json_object_get(json_object_get(l, "at"), "ur"));
    json_t *orbits = json_object_get(l, "orbits");
    int is_complete = json_is_true(json_object_get(l, "complete"));
    complete += is_complete;
    /* only the fields asked for */
    json_t *o0 = json_array_get(orbits, 0);
    if (o0) {
      ASSERT_EQ_INT((int)json_object_size(o0), 3);
      ASSERT_TRUE(json_is_string(json_object_get(o0, "found_by")));
    }
    char req[512], params[160];
    snprintf(params, sizeof params, P, ur);
    snprintf(req, sizeof req,
             "{\"params\":%s,\"kind\":\"overshoot\",\"finite_difference\":"
             "false}",
             params);
    http_resp ro;
    ASSERT_EQ_INT(http_do(PORT, "POST", "/orbit", JSON, req, &ro), 0);
    ASSERT_EQ_INT(ro.status, 200);
    json_t *oj = json_loads(ro.body, 0, NULL);
    json_t *alone = json_object_get(oj, "orbits");
    /* every orbit /orbit finds is in the cell; a complete cell has no
     * fewer */
    for (size_t k = 0; k < json_array_size(alone); k++) {
      double per = json_number_value(
          json_object_get(json_array_get(alone, k), "period"));
      int found = 0;
      for (size_t i = 0; i < json_array_size(orbits) && !found; i++) {
        double mp = json_number_value(
            json_object_get(json_array_get(orbits, i), "period"));
        found = lattice ? fabs(mp - per) < 1e-9 * per : mp == per;
      }
      if (!found)
        TEST_FAIL_("/map at ur %.17g lacks the orbit of period %.17g that "
                   "/orbit finds",
                   ur, per);
      test_checks_++;
    }
    if (is_complete)
      ASSERT_EQ_INT((int)json_array_size(orbits), (int)json_array_size(alone));
    compared += (int)json_array_size(alone);
    json_decref(oj);
    http_free(&ro);
    json_decref(l);
  }
  ASSERT_EQ_INT(lines, 8);
  if (lattice)
    ASSERT_TRUE(complete >= 3 && complete < 7 && compared >= 5);
  else
    ASSERT_TRUE(complete == 7 && compared >= 5);
  http_free(&r);
}

/* The samples of orbit 0 of an /orbit answer placed for a curve: one
 * period from its stick -> slip point to the next, starting in slip, the
 * modes changing at its three events only, each event sampled on both
 * sides; the columns asked for and no others. */
static void check_orbit_curve(const char *body, const char *what) {
  json_t *o = post("/orbit", body, 200);
  json_t *orb = json_array_get(json_object_get(o, "orbits"), 0);
  json_t *s = json_object_get(orb, "samples");
  json_t *t = json_object_get(s, "t"), *mode = json_object_get(s, "mode");
  size_t n = json_array_size(t);
  double period = json_number_value(json_object_get(orb, "period"));
  ASSERT_TRUE(n >= 8 && json_array_size(mode) == n);
  ASSERT_EQ_INT((int)json_object_size(s), 3); /* t, x2, mode */
  ASSERT_NEAR(json_number_value(json_array_get(t, 0)), 0, 0);
  ASSERT_NEAR(json_number_value(json_array_get(t, n - 1)), period,
              1e-9 * period);
  ASSERT_TRUE(!strcmp(json_string_value(json_array_get(mode, 0)), "slip"));
  int changes = 0;
  for (size_t i = 1; i < n; i++)
    if (strcmp(json_string_value(json_array_get(mode, i)),
               json_string_value(json_array_get(mode, i - 1)))) {
      changes++;
      /* both sides of the event at the same time */
      ASSERT_NEAR(json_number_value(json_array_get(t, i)),
                  json_number_value(json_array_get(t, i - 1)), 1e-12 * period);
    }
  ASSERT_EQ_INT(changes, 3);
  printf("curve of the paper's orbit, %s: %zu samples over %.6g\n", what, n,
         period);
  json_decref(o);
}

/* EVIDENCE: docs/api/simulate.md: an orbit's curve spans
 * exactly its period, from slip, in the request's units (dimensionless and
 * physical alike), with only the columns asked for. */
static void test_orbit_curves(void) {
  check_orbit_curve("{" PAPER ",\"kind\":\"overshoot\",\"samples\":{"
                    "\"tolerance\":1e-3,\"fields\":[\"t\",\"x2\",\"mode\"]}}",
                    "dimensionless");
  check_orbit_curve(
      "{\"physical\":{\"m1\":2.5,\"m2\":0.625,\"k1\":8,\"k2\":2,\"Fs\":"
      "0.724,\"Fr\":6.178,\"v0\":2},\"kind\":\"overshoot\",\"samples\":{"
      "\"tolerance\":1e-3,\"scale\":{\"v1\":2,\"v2\":2},\"fields\":[\"t\","
      "\"x2\",\"mode\"]}}",
      "physical");
}

int main(int argc, char **argv) {
  daemon_proc d;
  if (fixture_init(argc, argv))
    return 2;
  fixture_daemon_start(&d);
  test_map_against_orbit(NULL);
  test_map_against_orbit("\"search_every\":3,");
  test_orbit_curves();
  fixture_daemon_stop(&d);
  TEST_DONE();
}
