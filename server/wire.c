/*
 * wire.c: the bytes libmicrohttpd reads from its connections, followed
 * beside it, so that a chunk line too long for the connection's memory is
 * answered 413 by the daemon rather than 500 by the library.
 *
 * libmicrohttpd 0.9.75 reads a chunk's size line (its size and its
 * extensions) whole into the connection's buffer, and when the line does
 * not fit answers 500 itself, calling the daemon nowhere in between (its
 * 1.0 answers 413 there; Debian 12 has 0.9.75 alone).  The one call the
 * library makes while it reads such a line is recv(2), imported from libc:
 * the daemon defines recv, which the dynamic linker binds the library's
 * calls to (a definition in the executable comes before libc's), and reads
 * with recvfrom, which is the same system call.  Every byte goes to the
 * library unchanged.  On the sockets of the daemon's connections (a table
 * by descriptor, filled at a connection's start and emptied at its close;
 * any other socket, libpq's, is read as it would be) a small framer
 * follows the requests in them: a header block to its empty line, with its
 * Content-Length or its Transfer-Encoding, then the body, by its length or
 * chunk by chunk to its trailer's empty line.  A chunk line longer than
 * SRV__CHUNK_LINE bytes is refused: the bytes before it are given to the
 * library (so that it has the request's headers, and the daemon its
 * request), the socket is shut for reading (which the monitor is told is
 * not the client's doing: srv__wire_pending), and the library's next read
 * of it writes the 413 to the socket, as the daemon answers a body over its
 * limit (srv__send_raw_problem), and tells the library that the client has
 * gone, so that it closes the connection.  Where the framer and the
 * library could read a request differently (two lengths, a length and a
 * Transfer-Encoding, a folded header, a malformed chunk, a line that
 * starts with NUL, which the library takes for an empty one) the daemon
 * refuses the request itself or the library does (request.c), or the
 * framer cannot tell where a block ends, and it stops following that
 * connection: it never refuses what it does
 * not read the library's way.
 *
 * All of it runs on libmicrohttpd's one I/O thread, where the connections
 * start and close, requests are admitted and completed, and the library
 * reads; the table's slots are atomic only for other threads' recv calls,
 * which look and find nothing.
 */
#undef _FORTIFY_SOURCE /* its recv is an inline function of the header's */
#define _GNU_SOURCE
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/socket.h>

#include "internal.h"

enum {
  W_HEAD,     /* a header block: its lines */
  W_LENGTH,   /* a body of Content-Length bytes */
  W_SIZE,     /* a chunk's size line */
  W_DATA,     /* a chunk's data */
  W_DATA_END, /* the line end after a chunk's data */
  W_TRAILER,  /* the trailer's lines, to its empty line */
  W_OFF       /* not followed any more: the connection is refused */
};

/* Descriptors below this many are followed: the hard limit on open files
 * when the table is made (what the daemon may raise its soft limit to),
 * at most 2^20. */
static _Atomic(srv__conn *) *table;
/* by descriptor too: 1 while a refusal waits for the library's next read
 * (read by other threads, which may not follow a connection's pointer) */
static atomic_uchar *pending;
static atomic_size_t table_n; /* set once the table is */
static pthread_once_t table_once = PTHREAD_ONCE_INIT;

static void table_make(void) {
  struct rlimit rl;
  size_t n = 1u << 20;
  if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_max != RLIM_INFINITY &&
      rl.rlim_max < n)
    n = (size_t)rl.rlim_max;
  /* untouched pages of zeros: what is used is what the descriptors reach */
  table = calloc(n, sizeof *table);
  pending = calloc(n, sizeof *pending);
  if (table && pending)
    atomic_store(&table_n, n);
}

int srv__wire_open(srv__conn *cn) {
  pthread_once(&table_once, table_make);
  memset(&cn->wire, 0, sizeof cn->wire);
  cn->wire.fresh = 1;
  if (cn->fd < 0 || (size_t)cn->fd >= atomic_load(&table_n))
    return -1;
  atomic_store(&table[cn->fd], cn);
  return 0;
}

void srv__wire_close(srv__conn *cn) {
  if (cn->fd >= 0 && (size_t)cn->fd < atomic_load(&table_n) &&
      atomic_load(&table[cn->fd]) == cn) {
    atomic_store(&pending[cn->fd], 0);
    atomic_store(&table[cn->fd], NULL);
  }
}

int srv__wire_pending(int fd) {
  return fd >= 0 && (size_t)fd < atomic_load(&table_n) &&
         atomic_load(&pending[fd]);
}

/* ---- the framer ---------------------------------------------------------- */

/* Whether the line @a s (@a n bytes kept) starts with header @a name and
 * its colon, in any case; then *value is where its value starts. */
static int header_is(const char *s, size_t n, const char *name,
                     const char **value) {
  size_t k = strlen(name);
  if (n <= k || s[k] != ':' || strncasecmp(s, name, k))
    return 0;
  *value = s + k + 1;
  return 1;
}

/* The value @a v (to @a end) without its surrounding blanks. */
static void trim(const char **v, const char **end) {
  while (*v < *end && (**v == ' ' || **v == '\t'))
    (*v)++;
  while (*end > *v && ((*end)[-1] == ' ' || (*end)[-1] == '\t'))
    (*end)--;
}

/* The next chunk's size line. */
static void to_size(srv__wire *w) {
  w->state = W_SIZE;
  w->line = w->digits = 0;
  w->in_size = 1;
  w->size = 0;
}

/* A line of a header block, whole: its first SRV__WIRE_KEEP bytes in
 * w->keep, its length in w->line, whether it ends in CR in w->cr. */
static void head_line(srv__wire *w) {
  int whole = w->line <= SRV__WIRE_KEEP;
  const char *v, *end = w->keep + w->kept - (whole && w->cr);
  size_t n = (size_t)(end - w->keep);
  if (w->line - (w->line > 0 && w->cr) == 0) {
    if (w->fresh) /* empty lines before a request line are skipped */
      return;
    /* the block's end: how its body is framed */
    if (w->odd || w->lengths > 1 || w->encodings > 1 ||
        (w->lengths && w->encodings) || w->encodings > w->chunked)
      w->state = W_OFF; /* refused by the daemon or the library */
    else if (w->chunked)
      to_size(w);
    else if (w->lengths && w->left)
      w->state = W_LENGTH;
    w->fresh = 1;
    w->lengths = w->chunked = w->encodings = w->odd = 0;
    return;
  }
  if (w->fresh) { /* the request line */
    w->fresh = 0;
    w->left = 0;
    return;
  }
  if (w->keep[0] == ' ' || w->keep[0] == '\t') {
    w->odd = 1; /* a folded line: the library joins it to the header */
    return;
  }
  if (header_is(w->keep, n, "content-length", &v)) {
    w->lengths++;
    trim(&v, &end);
    unsigned long long x = 0;
    int digits = 0;
    for (; v < end && *v >= '0' && *v <= '9' && digits < 19; v++, digits++)
      x = 10 * x + (unsigned)(*v - '0');
    if (!whole || !digits || v != end)
      w->odd = 1;
    w->left = x;
  } else if (header_is(w->keep, n, "transfer-encoding", &v)) {
    w->encodings++;
    trim(&v, &end);
    if (whole && end - v == 7 && !strncasecmp(v, "chunked", 7))
      w->chunked++;
  }
}

static int hex(int ch) {
  if (ch >= '0' && ch <= '9')
    return ch - '0';
  ch |= 0x20; /* lower case */
  return ch >= 'a' && ch <= 'f' ? ch - 'a' + 10 : -1;
}

/* Follow the @a n bytes at @a p.  -1 when no chunk line in them is over
 * the limit; else the offset in them at which such a line starts (0 when
 * it started in an earlier read). */
static long follow(srv__wire *w, const char *p, size_t n) {
  size_t i = 0;
  while (i < n && w->state != W_OFF) {
    switch (w->state) {
    case W_LENGTH:
    case W_DATA: {
      unsigned long long k = n - i < w->left ? n - i : w->left;
      i += (size_t)k;
      w->left -= k;
      if (!w->left)
        w->state = w->state == W_DATA ? W_DATA_END : W_HEAD;
      w->cr = 0;
      break;
    }
    case W_DATA_END: /* CRLF, or LF */
      if (p[i] == '\n')
        to_size(w);
      else if (p[i] != '\r' || w->cr++)
        w->state = W_OFF; /* the library refuses it */
      i++;
      break;
    case W_SIZE:
      for (; i < n; i++) {
        int ch = (unsigned char)p[i];
        if (ch == '\n') {
          i++;
          if (!w->digits || w->digits > 15) {
            w->state = W_OFF; /* malformed, or over 2^60: refused */
          } else if (w->size) {
            w->state = W_DATA;
            w->left = w->size;
          } else {
            w->state = W_TRAILER; /* the last chunk */
            w->line = w->kept = 0;
            w->cr = 0;
          }
          break;
        }
        w->line++;
        if (w->in_size && hex(ch) >= 0) {
          w->size = 16 * w->size + (unsigned)hex(ch);
          w->digits++;
        } else {
          w->in_size = 0;
        }
        /* over the limit whether a CR ends it or not */
        if (w->line > SRV__CHUNK_LINE + 1 ||
            (w->line == SRV__CHUNK_LINE + 1 && ch != '\r'))
          return w->line > i + 1 ? 0 : (long)(i + 1 - w->line);
      }
      break;
    case W_HEAD:
    case W_TRAILER: {
      const char *lf = memchr(p + i, '\n', n - i);
      size_t k = lf ? (size_t)(lf - (p + i)) : n - i;
      if (w->kept < SRV__WIRE_KEEP) {
        size_t c = SRV__WIRE_KEEP - w->kept < k ? SRV__WIRE_KEEP - w->kept : k;
        memcpy(w->keep + w->kept, p + i, c);
        w->kept += c;
      }
      w->line += k;
      if (k)
        w->cr = p[i + k - 1] == '\r';
      i += k;
      if (!lf)
        break;
      i++; /* the LF */
      if (w->kept && !w->keep[0]) {
        /* the library takes a line that starts with NUL for an empty
         * one: where a block ends is not read its way here */
        w->state = W_OFF;
        break;
      }
      if (w->state == W_HEAD)
        head_line(w);
      else if (w->line - (w->line > 0 && w->cr) == 0)
        w->state = W_HEAD, w->fresh = 1; /* the trailer's end */
      w->line = w->kept = 0;
      w->cr = 0;
      break;
    }
    }
  }
  return -1;
}

/* ---- libmicrohttpd's reads ----------------------------------------------- */

/* The 413 of a chunk line over the limit, written to the socket for the
 * request of @a cn when the daemon has not answered it; then the library
 * is told that the client has gone (0 bytes), and closes the connection. */
static ssize_t refuse(srv__conn *cn) {
  srv__req *r = cn->req;
  cn->wire.state = W_OFF;
  atomic_store(&pending[cn->fd], 0);
  if (r && !r->done) {
    char detail[128];
    snprintf(detail, sizeof detail,
             "a chunk line (its size and extensions) is over the limit of "
             "%d bytes",
             SRV__CHUNK_LINE);
    srv__send_raw_problem(r, API_P_BODY_TOO_LARGE, detail, "max_chunk_line",
                          SRV__CHUNK_LINE);
  }
  return 0;
}

ssize_t recv(int fd, void *buf, size_t len, int flags) {
  srv__conn *cn = NULL;
  if (!flags && fd >= 0 && (size_t)fd < atomic_load(&table_n))
    cn = atomic_load(&table[fd]);
  if (cn && atomic_load(&pending[fd]))
    return refuse(cn);
  ssize_t n = recvfrom(fd, buf, len, flags, NULL, NULL);
  if (!cn || n <= 0 || cn->wire.state == W_OFF)
    return n;
  long at = follow(&cn->wire, buf, (size_t)n);
  if (at < 0)
    return n;
  if (at > 0) {
    /* the bytes before the line first, so that the library has the
     * request's headers and the daemon its request: the library's next
     * read, woken by the socket's end, refuses (a short read alone does
     * not bring it back).  Until then the socket's end is not the
     * client's: srv__wire_pending tells the monitor so. */
    atomic_store(&pending[fd], 1);
    shutdown(fd, SHUT_RD);
    return at;
  }
  if (cn->req && cn->req->done) {
    /* answered already: the library's way, as before */
    cn->wire.state = W_OFF;
    return n;
  }
  return refuse(cn);
}
