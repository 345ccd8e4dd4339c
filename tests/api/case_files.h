/*
 * case_files.h: the files of an api case (tests/api/cases/<endpoint>-<name>/,
 * test_case.c), read for the tests that answer the cases.
 */
#ifndef SS_TEST_CASE_FILES_H
#define SS_TEST_CASE_FILES_H

#include <stddef.h>

#include "stickslip_api.h"

/* The bytes of the file at @a path, NUL-terminated (malloc'd), their count
 * in *len; NULL when it cannot be read. */
char *case_slurp(const char *path, size_t *len);

/* The limits of limits.json at @a path, over those in @a lim: each key names
 * a field of api_limits.  0 (also when there is no such file), or -1 when
 * the file is not an object or names an unknown limit. */
int case_limits(const char *path, api_limits *lim);

/* The computing endpoint that case directory @a name (its base name) is
 * for, by the label it starts with; api_endpoint_count() when none. */
size_t case_endpoint(const char *name);

#endif
