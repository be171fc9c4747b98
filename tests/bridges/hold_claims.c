// LD_PRELOAD library for tests: holds a body claim for as long as a test wants. While
// the file named by $AFHUB_TEST_HOLD_CLAIMS exists, kill(pid, 0), which a claim calls
// to ask whether a listed body's owner lives (hub/client/src/body_claims.cpp), says
// "hold_claims: a claim held" on stderr and waits for the file to go.
#define _GNU_SOURCE
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/syscall.h>
#include <unistd.h>

int kill(pid_t pid, int sig) {
  const char* hold = getenv("AFHUB_TEST_HOLD_CLAIMS");
  if (sig == 0 && hold && access(hold, F_OK) == 0) {
    fputs("hold_claims: a claim held\n", stderr);
    while (access(hold, F_OK) == 0) usleep(10000);
  }
  return (int)syscall(SYS_kill, pid, sig);
}
