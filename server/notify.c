/*
 * notify.c: the service manager's notification protocol, as sd_notify(3)
 * documents it: one datagram of newline-separated VARIABLE=value lines on
 * an AF_UNIX SOCK_DGRAM socket whose address is $NOTIFY_SOCKET, a file
 * system path, or an abstract name when it starts with '@' (that byte
 * then stands for the leading NUL).  Written here rather than linked from
 * libsystemd: the protocol is this one datagram, and the daemon then
 * builds and runs alike where systemd is absent (a container, another
 * init), where the variable is unset and nothing is sent.
 */
#define _GNU_SOURCE
#include <errno.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include "notify.h"

int srv_notify(const char *state) {
  const char *path = getenv("NOTIFY_SOCKET");
  size_t n = path ? strlen(path) : 0, len = strlen(state);
  struct sockaddr_un sa;
  if (!n)
    return 0;
  if ((path[0] != '/' && path[0] != '@') || n >= sizeof sa.sun_path) {
    errno = EAFNOSUPPORT;
    return -1;
  }
  memset(&sa, 0, sizeof sa);
  sa.sun_family = AF_UNIX;
  memcpy(sa.sun_path, path, n);
  if (path[0] == '@')
    sa.sun_path[0] = 0;
  int fd = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0)
    return -1;
  /* an abstract name is as long as the address says: no NUL counted */
  ssize_t sent =
      sendto(fd, state, len, MSG_NOSIGNAL, (struct sockaddr *)&sa,
             (socklen_t)(offsetof(struct sockaddr_un, sun_path) + n));
  int err = errno;
  close(fd);
  errno = err;
  return sent == (ssize_t)len ? 0 : -1;
}
