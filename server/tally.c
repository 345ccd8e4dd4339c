/*
 * tally.c: counts by key (a client's address as text), and how many keys
 * count something: what each client holds of the memory budget (reply.c),
 * and each address's connections (monitor.c).  A key whose count comes back
 * to 0 is forgotten, so the table holds only the clients of the moment.
 */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "internal.h"

#define TALLY_BUCKETS 1024

typedef struct entry {
  struct entry *next;
  long count;
  char key[SRV_CLIENT_KEY];
} entry;

struct srv__tally {
  pthread_mutex_t mu;
  entry *bucket[TALLY_BUCKETS];
  unsigned keys; /* entries, all with a count other than 0 */
  long total;    /* the sum of the counts */
};

srv__tally *srv__tally_new(void) {
  srv__tally *t = calloc(1, sizeof *t);
  if (t)
    pthread_mutex_init(&t->mu, NULL);
  return t;
}

void srv__tally_free(srv__tally *t) {
  if (!t)
    return;
  for (size_t i = 0; i < TALLY_BUCKETS; i++)
    while (t->bucket[i]) {
      entry *e = t->bucket[i];
      t->bucket[i] = e->next;
      free(e);
    }
  pthread_mutex_destroy(&t->mu);
  free(t);
}

/* The bucket of @a key: FNV-1a of its text. */
static entry **bucket_of(srv__tally *t, const char *key) {
  unsigned h = 2166136261u;
  for (const char *s = key; *s; s++)
    h = (h ^ (unsigned char)*s) * 16777619u;
  return &t->bucket[h % TALLY_BUCKETS];
}

long srv__tally_add(srv__tally *t, const char *key, long delta) {
  if (!t || !delta)
    return srv__tally_get(t, key, NULL, NULL);
  pthread_mutex_lock(&t->mu);
  entry **at = bucket_of(t, key);
  while (*at && strcmp((*at)->key, key) != 0)
    at = &(*at)->next;
  entry *e = *at;
  long count = 0;
  if (!e && (e = calloc(1, sizeof *e))) {
    /* a key the table cannot hold is not counted: it limits nothing */
    strncpy(e->key, key, sizeof e->key - 1);
    e->next = NULL;
    *at = e;
    t->keys++;
  }
  if (e) {
    count = e->count += delta;
    t->total += delta;
    if (count == 0) {
      *at = e->next;
      free(e);
      t->keys--;
    }
  }
  pthread_mutex_unlock(&t->mu);
  return count;
}

long srv__tally_get(srv__tally *t, const char *key, unsigned *keys,
                    long *total) {
  long count = 0;
  if (!t) {
    if (keys)
      *keys = 0;
    if (total)
      *total = 0;
    return 0;
  }
  pthread_mutex_lock(&t->mu);
  for (entry *e = *bucket_of(t, key); e; e = e->next)
    if (strcmp(e->key, key) == 0) {
      count = e->count;
      break;
    }
  if (keys)
    *keys = t->keys;
  if (total)
    *total = t->total;
  pthread_mutex_unlock(&t->mu);
  return count;
}
