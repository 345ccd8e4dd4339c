/*
 * arena.c: jansson's allocator, a bump arena per thread while a scope is
 * open.  Serving a small request builds and frees two JSON trees, the
 * request's and the answer's: some 300 malloc and free calls for an /orbit
 * from a guess, which cost as much CPU as the solve itself, and more when
 * other threads' frees fragment the heap (malloc_consolidate).  Within a
 * scope (api__handle, api_batch_open), a value is taken from the thread's
 * current chunk by moving a pointer, its free does nothing, and the scope's
 * end gives every chunk taken since its beginning back at once.
 *
 * Outside a scope, and on threads that never open one, the allocator is
 * malloc and free.  A free recognises an arena's memory by its address (the
 * thread's chunks, a handful: each is twice the last), so a value made
 * before a scope may be freed inside it.  The one rule: a value made in a
 * scope does not outlive it (arena.h).
 */
#include <stdint.h>
#include <stdlib.h>

#include "arena.h"

/* The first chunk holds a request's tree and an /orbit answer's. */
#define CHUNK_FIRST ((size_t)64 * 1024)
#define ALIGN 16 /* what malloc guarantees on 64-bit targets */

typedef struct chunk {
  struct chunk *prev; /* the chunk taken before, or NULL */
  size_t cap, used;   /* bytes of data[] */
  _Alignas(ALIGN) unsigned char data[];
} chunk;

typedef struct arena {
  chunk *head; /* the chunk being filled; NULL when no scope is open */
  int depth;   /* scopes open */
  int paused;  /* api__json_dumps is writing text that outlives it */
} arena;

static _Thread_local arena here;

static void *arena_malloc(size_t n) {
  arena *a = &here;
  if (a->depth == 0 || a->paused)
    return malloc(n);
  size_t need = (n + ALIGN - 1) & ~(size_t)(ALIGN - 1);
  chunk *c = a->head;
  if (!c || c->cap - c->used < need) {
    size_t cap = c ? 2 * c->cap : CHUNK_FIRST;
    while (cap < need)
      cap *= 2;
    chunk *nc = malloc(sizeof *nc + cap);
    if (!nc)
      return NULL;
    nc->prev = c;
    nc->cap = cap;
    nc->used = 0;
    a->head = c = nc;
  }
  void *p = c->data + c->used;
  c->used += need;
  return p;
}

static int in_arena(const void *p) {
  uintptr_t u = (uintptr_t)p;
  for (const chunk *c = here.head; c; c = c->prev)
    if (u >= (uintptr_t)c->data && u < (uintptr_t)(c->data + c->cap))
      return 1;
  return 0;
}

static void arena_free(void *p) {
  if (p && !in_arena(p))
    free(p);
}

/* Installed before main, while no thread allocates through jansson. */
__attribute__((constructor)) static void arena_install(void) {
  json_set_alloc_funcs(arena_malloc, arena_free);
}

void api__arena_begin(api_arena_mark *m) {
  m->chunk = here.head;
  m->used = here.head ? here.head->used : 0;
  here.depth++;
}

void api__arena_end(const api_arena_mark *m) {
  while (here.head && here.head != m->chunk) {
    chunk *c = here.head;
    here.head = c->prev;
    free(c);
  }
  if (here.head)
    here.head->used = m->used;
  here.depth--;
}

char *api__json_dumps(const json_t *j, size_t flags) {
  here.paused++;
  char *s = json_dumps(j, flags);
  here.paused--;
  return s;
}
