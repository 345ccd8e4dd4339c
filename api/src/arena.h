/*
 * arena.h: the memory of the codec's JSON trees (arena.c).  Within a scope
 * on one thread, jansson's values come from a bump arena instead of malloc
 * and are freed all at once when the scope ends.
 */
#ifndef SS_API_ARENA_H
#define SS_API_ARENA_H

#include <jansson.h>
#include <stddef.h>

/* Where a scope began: api__arena_end gives back what was taken since. */
typedef struct api_arena_mark {
  void *chunk;
  size_t used;
} api_arena_mark;

/* Open a scope on this thread (scopes nest).  ALWAYS: every JSON value made
 * in it is freed (json_decref) before api__arena_end, on this thread; what
 * outlives it (an answer's text, a batch item's body) is written with
 * malloc'd memory (writer.c), never kept as a json_t. */
void api__arena_begin(api_arena_mark *m);
void api__arena_end(const api_arena_mark *m);

/* json_dumps with malloc'd text (its caller frees it with free()), also
 * inside a scope. */
char *api__json_dumps(const json_t *j, size_t flags);

#endif
