// LD_PRELOAD library for tests: stops its process (SIGSTOP) just before it sends its
// registration to the hub (iceoryx's first message on RouDi's socket, /tmp/roudi, a
// REG: "1,<runtime name>,..."), so that a test can kill the hub while the process
// registers and then let it run on. Once per test: only while the file named by
// $AFHUB_TEST_STOP_BEFORE_REGISTRATION does not exist, which it then creates (a process
// that re-executes keeps the library).
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <unistd.h>

static int to_roudi(int fd) {
  struct sockaddr_un peer;
  socklen_t length = sizeof peer;
  memset(&peer, 0, sizeof peer);
  return getpeername(fd, (struct sockaddr*)&peer, &length) == 0 && peer.sun_family == AF_UNIX &&
         strcmp(peer.sun_path, "/tmp/roudi") == 0;
}

ssize_t sendto(int fd, const void* buffer, size_t size, int flags, const struct sockaddr* to,
               socklen_t to_size) {
  const char* once = getenv("AFHUB_TEST_STOP_BEFORE_REGISTRATION");
  if (once && size >= 2 && memcmp(buffer, "1,", 2) == 0 && to_roudi(fd)) {
    const int marker = open(once, O_WRONLY | O_CREAT | O_EXCL, 0600);
    if (marker >= 0) {
      close(marker);
      fputs("stop_before_registration: stopped\n", stderr);
      raise(SIGSTOP);
    }
  }
  return (ssize_t)syscall(SYS_sendto, fd, buffer, size, flags, to, to_size);
}
