/* Ctrl-C handling (interrupt.h). */
#include "interrupt.h"

volatile sig_atomic_t mocapctl_interrupted = 0;

static void on_interrupt(int sig)
{
    if (mocapctl_interrupted) {
        signal(sig, SIG_DFL);
        raise(sig);
        return;
    }
    mocapctl_interrupted = 1;
}

void mocapctl_catch_interrupt(void) { signal(SIGINT, on_interrupt); }
