// LD_PRELOAD library for tests: sends its own process SIGINT as it calls execve (a
// client re-executing itself after a hub loss), and gives its other threads 0.2 ms to
// take it before the exec goes on (less than a 1 kHz loop takes to see the flag and
// end the old image): a Ctrl-C in the last microseconds of the old image.
// Once: only while the marker file named by AFHUB_TEST_SIGINT_AT_EXEC does not exist,
// which it then creates (the new image keeps the library and the variable).
#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

int execve(const char* path, char* const argv[], char* const envp[]) {
  const char* once = getenv("AFHUB_TEST_SIGINT_AT_EXEC");
  if (once) {
    const int marker = (int)syscall(SYS_openat, AT_FDCWD, once, O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (marker >= 0) {
      close(marker);
      kill(getpid(), SIGINT);
      const struct timespec taken = {0, 200 * 1000};
      nanosleep(&taken, NULL);
    }
  }
  return (int)syscall(SYS_execve, path, argv, envp);
}
