/* Ctrl-C for mocapctl's commands: the first asks the running command to finish (flush, close,
 * report); a second ends the process at once, for a command blocked in I/O that cannot see the
 * first (opening a named pipe nobody writes, writing to a terminal nobody reads). */
#ifndef MOCAPCTL_INTERRUPT_H
#define MOCAPCTL_INTERRUPT_H

#include <signal.h>

/* Set by the first Ctrl-C; the commands' loops poll it. */
extern volatile sig_atomic_t mocapctl_interrupted;

void mocapctl_catch_interrupt(void);

#endif
