/*
 * case_files.c: the files of an api case, read (case_files.h).
 */
#include "case_files.h"

#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

char *case_slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f)
    return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *b = n >= 0 ? malloc((size_t)n + 1) : NULL;
  if (!b || fread(b, 1, (size_t)n, f) != (size_t)n) {
    fclose(f);
    free(b);
    return NULL;
  }
  fclose(f);
  b[n] = 0;
  *len = (size_t)n;
  return b;
}

int case_limits(const char *path, api_limits *lim) {
  FILE *f = fopen(path, "rb");
  if (!f)
    return 0;
  fclose(f);
  json_t *j = json_load_file(path, 0, NULL);
  const char *k;
  json_t *v;
  if (!json_is_object(j)) {
    json_decref(j);
    return -1;
  }
  json_object_foreach(j, k, v) {
    double x = json_number_value(v);
    if (!strcmp(k, "max_seconds"))
      lim->max_seconds = x;
    else if (!strcmp(k, "max_samples"))
      lim->max_samples = (size_t)x;
    else if (!strcmp(k, "max_events"))
      lim->max_events = (size_t)x;
    else if (!strcmp(k, "max_event_list"))
      lim->max_event_list = (size_t)x;
    else if (!strcmp(k, "max_horizon"))
      lim->max_horizon = x;
    else if (!strcmp(k, "max_orbits"))
      lim->max_orbits = (int)x;
    else if (!strcmp(k, "max_points"))
      lim->max_points = (size_t)x;
    else if (!strcmp(k, "max_map_cells"))
      lim->max_map_cells = (size_t)x;
    else if (!strcmp(k, "max_basin_cells"))
      lim->max_basin_cells = (size_t)x;
    else {
      json_decref(j);
      return -1;
    }
  }
  json_decref(j);
  return 0;
}

size_t case_endpoint(const char *name) {
  size_t ep = api_endpoint_count();
  for (size_t i = 0; i < api_endpoint_count(); i++) {
    const api_endpoint *row = api_endpoint_at(i);
    size_t n = strlen(row->label);
    if (row->run_class == API_RUN_COMPUTE && !strncmp(name, row->label, n) &&
        name[n] == '-')
      ep = i;
  }
  return ep;
}
