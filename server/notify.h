/*
 * notify.h: systemd's readiness notification (notify.c), for a unit of
 * Type=notify.
 */
#ifndef SS_SERVER_NOTIFY_H
#define SS_SERVER_NOTIFY_H

/* Send @a state ("READY=1\nSTATUS=...") to the service manager at
 * $NOTIFY_SOCKET: 0 when sent or when no manager asks (the variable unset
 * or empty), -1 (errno set) when it could not be sent. */
int srv_notify(const char *state);

#endif
