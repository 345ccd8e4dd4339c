/*
 * scan.h: a check of JSON text that builds no tree (scan.c), for the text
 * that is parsed later, once, where it is used (a batch's items).
 */
#ifndef SS_API_SCAN_H
#define SS_API_SCAN_H

#include <jansson.h>
#include <stddef.h>

/* A member of the object scanned: its key's text (without the quotes) and
 * its value's text. */
typedef struct api_scan_member {
  const char *key, *value;
  size_t key_len, value_len;
} api_scan_member;

enum { API_SCAN_MEMBERS = 4 };

/* The members of the outermost object scanned, the first API_SCAN_MEMBERS
 * of them; n counts them all. */
typedef struct api_scan_top {
  api_scan_member m[API_SCAN_MEMBERS];
  size_t n;
} api_scan_top;

/* The end of the JSON value at @a p (before @a end), nested at most
 * @a depth deep, when it is of the plain kind that jansson reads into the
 * same values (JSON_REJECT_DUPLICATES, no overflow): strings of printable
 * ASCII, keys without escapes and none twice in an object, numbers that fit
 * a 64-bit integer or a double.  NULL for anything else, valid or not, left
 * to jansson and its own problem.  @a top, when given, gets the members of
 * the value if it is an object. */
const char *api__json_scan(const char *p, const char *end, int depth,
                           api_scan_top *top);

/* The tree of the JSON object or array in @a p .. @a end (whitespace
 * around it), nested at most @a depth deep, built straight from the text
 * when api__json_scan vouches for it: the values json_loadb reads from it
 * with JSON_REJECT_DUPLICATES, in the same order, made with the same
 * allocator, without jansson's lexer (a third of an /orbit body's parse).
 * NULL for anything else, valid or not, or when out of memory: the caller
 * parses with jansson, whose problem stands. */
json_t *api__json_build(const char *p, const char *end, int depth);

#endif
