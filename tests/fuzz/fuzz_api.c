/*
 * fuzz_api.c: the request decoder and the endpoints on arbitrary bytes.
 *
 * Every input, for every computing endpoint, must give a 200, 400 or 422
 * whose body is valid JSON (so with no NaN or Infinity), within small compute
 * limits; anything else aborts.  Built as a libFuzzer target with clang
 * (-DSTICKSLIP_FUZZ=ON) and, with replay.c, as an ordinary test that runs
 * the stored corpus (tests/fuzz/corpus).
 */
#include <jansson.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "stickslip.h"
#include "stickslip_api.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static int init;
  api_limits lim;
  if (!init) {
    ss_gsl_quiet();
    init = 1;
  }
  api_limits_default(&lim);
  lim.max_samples = 2000;
  lim.max_events = 20000;
  lim.max_event_list = 2000;
  lim.max_horizon = 1e4;
  lim.max_seconds = 0.2;
  lim.max_orbits = 4;
  for (size_t ep = 0; ep < api_endpoint_count(); ep++) {
    if (api_endpoint_at(ep)->run_class != API_RUN_COMPUTE)
      continue;
    api_response r;
    int st = api_handle(ep, (const char *)data, size, &lim, NULL, &r);
    if (st != 200 && st != 400 && st != 422) {
      fprintf(stderr, "endpoint %zu answered %d: %s\n", ep, st,
              r.body ? r.body : "(no body)");
      abort();
    }
    json_error_t je;
    json_t *j = r.body ? json_loads(r.body, 0, &je) : NULL;
    /* jansson refuses NaN and Infinity tokens, so a body it parses has
     * none (the words may appear inside strings, quoting the input) */
    if (!j) {
      fprintf(stderr, "endpoint %zu: bad body: %.300s\n", ep,
              r.body ? r.body : "(none)");
      abort();
    }
    json_decref(j);
    api_response_free(&r);
  }
  return 0;
}
