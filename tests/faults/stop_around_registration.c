// LD_PRELOAD library for tests: stops its process (SIGSTOP) around its registration with
// the hub, so that a test can kill or replace the hub then, and let it run on. Once per
// test: only while the marker file named by the variable does not exist, which it then
// creates (a process that re-executes keeps the library).
//   AFHUB_TEST_STOP_BEFORE_REGISTRATION: just before it sends its registration (iceoryx's
//     first message on RouDi's socket, /tmp/roudi, a REG: "1,<runtime name>,...").
//   AFHUB_TEST_STOP_AFTER_REGISTRATION: at the first read of the hub's identity (a file
//     hub.id) after it sent its registration: the hub-loss watcher's first look, once
//     registered (or a look of the registration's guard, should registering take 20 ms).
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/un.h>
#include <unistd.h>

static _Atomic int registration_sent;

static int to_roudi(int fd) {
  struct sockaddr_un peer;
  socklen_t length = sizeof peer;
  memset(&peer, 0, sizeof peer);
  return getpeername(fd, (struct sockaddr*)&peer, &length) == 0 && peer.sun_family == AF_UNIX &&
         strcmp(peer.sun_path, "/tmp/roudi") == 0;
}

static void stop_once(const char* variable, const char* said) {
  const char* once = getenv(variable);
  if (!once) return;
  const int marker = (int)syscall(SYS_openat, AT_FDCWD, once, O_WRONLY | O_CREAT | O_EXCL, 0600);
  if (marker < 0) return;
  close(marker);
  fputs(said, stderr);
  raise(SIGSTOP);
}

ssize_t sendto(int fd, const void* buffer, size_t size, int flags, const struct sockaddr* to,
               socklen_t to_size) {
  if (size >= 2 && memcmp(buffer, "1,", 2) == 0 && to_roudi(fd)) {
    stop_once("AFHUB_TEST_STOP_BEFORE_REGISTRATION", "stop_around_registration: stopped before\n");
    registration_sent = 1;
  }
  return (ssize_t)syscall(SYS_sendto, fd, buffer, size, flags, to, to_size);
}

static void before_open(const char* path) {
  const size_t length = path ? strlen(path) : 0;
  if (registration_sent && length >= 7 && strcmp(path + length - 7, "/hub.id") == 0)
    stop_once("AFHUB_TEST_STOP_AFTER_REGISTRATION", "stop_around_registration: stopped after\n");
}

int open(const char* path, int flags, ...) {
  va_list rest;
  va_start(rest, flags);
  const mode_t mode =
      (flags & O_CREAT) || (flags & __O_TMPFILE) == __O_TMPFILE ? va_arg(rest, mode_t) : 0;
  va_end(rest);
  before_open(path);
  return (int)syscall(SYS_openat, AT_FDCWD, path, flags, mode);
}

// The same on x86_64, where files are 64-bit alike.
int open64(const char* path, int flags, ...) __attribute__((alias("open"), copy(open)));
