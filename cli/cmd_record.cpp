// `afhub record`: every body's state, the world's and the scene (and with options the
// commands and devices) to an MCAP file at the rate it is published, until Ctrl-C or --duration.
// `afhub record --recover FILE`: gives a file that was cut off its index back.
#include <fcntl.h>
#include <unistd.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "afhub/hub/hub_loss.hpp"
#include "afhub/hub/startup_wait.hpp"
#include "afhub/record/mcap_reader.hpp"
#include "afhub/record/recorder.hpp"
#include "afhub/record/recording_lock.hpp"
#include "afhub/rt/stop_signal.hpp"
#include "afhub/shm_layout/error.hpp"
#include "commands.hpp"
#include "realtime_options.hpp"
#include "time_options.hpp"

namespace afhub::cli {
namespace {

struct RecordCliOptions {
  mcap::RecordOptions record;
  std::string compression = "zstd";
  double buffer_mb = 256;
  double wait_s = 0.0;
  std::string recover;
  bool overwrite = false;
  RealtimeOptions realtime;
};

std::string progress_line(const mcap::RecordProgress& p, double mb_per_s) {
  char line[256];
  std::snprintf(
      line, sizeof line,
      "recorded %.1f s  %llu channels  %llu messages  %.1f MB  %.1f MB/s  dropped %llu  "
      "missed %llu  commands replaced %llu",
      p.seconds, static_cast<unsigned long long>(p.channels),
      static_cast<unsigned long long>(p.messages), static_cast<double>(p.file_bytes) / 1e6,
      mb_per_s, static_cast<unsigned long long>(p.dropped),
      static_cast<unsigned long long>(p.missed), static_cast<unsigned long long>(p.replaced));
  return line;
}

// "run.mcap" as the `n`-th file after it: "run.n.mcap".
std::string numbered(const std::string& path, unsigned n) {
  const std::filesystem::path file(path);
  return (file.parent_path() / (file.stem().string() + "." + std::to_string(n) +
                                (file.has_extension() ? file.extension().string() : "")))
      .string();
}

bool holds_something(const std::string& path) {
  std::error_code error;
  return std::filesystem::is_regular_file(path, error) &&
         std::filesystem::file_size(path, error) > 0 && !error;
}

// Throws when another recorder (or a recovery) writes `path`.
void require_unlocked(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return;
  const struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  mcap::lock_recording(fd, path);
}

bool taken(const std::string& path) {
  std::error_code error;
  if (holds_something(path) ||
      (std::filesystem::exists(path, error) && !std::filesystem::is_regular_file(path, error)))
    return true;  // a directory, a FIFO nobody reads: not a file to record into
  try {
    require_unlocked(path);
    return false;
  } catch (const Error&) {
    return true;
  }
}

// A recording is not lost to a repeated command line: a file there is refused.
void refuse_a_recording_there(const RecordCliOptions& options) {
  const std::string& path = options.record.output;
  if (reattach_count() > 0 || options.overwrite || !holds_something(path)) return;
  require_unlocked(path);  // another recorder's file is said as such
  throw Error(path + " exists: give another -o, or --overwrite to record over it");
}

// A recorder re-attached to a new hub takes the next number no file has and no other
// recorder writes, chosen once connected (a file written while the hub was down counts).
// A FIFO or a device is written again as it is: numbered, it became a new regular file.
void number_a_reattached_output(RecordCliOptions& options) {
  const std::string first = options.record.output;
  std::error_code error;
  if (reattach_count() == 0 ||
      (std::filesystem::exists(first, error) && !std::filesystem::is_regular_file(first, error)))
    return;
  unsigned n = reattach_count();
  do options.record.output = numbered(first, n++);
  while (taken(options.record.output));
}

int run_recover(const std::string& path) {
  const mcap::ScanResult result = mcap::recover(path);
  if (result.indexed)
    std::printf("%s: complete (%llu messages in %llu chunks, with its summary): left as it is\n",
                path.c_str(), static_cast<unsigned long long>(result.messages),
                static_cast<unsigned long long>(result.chunks));
  else
    std::printf("%s: %s; rewrote %llu messages in %llu chunks with a summary and index\n",
                path.c_str(),
                result.complete ? "complete but without a summary"
                                : ("was cut off: " + result.cut_off).c_str(),
                static_cast<unsigned long long>(result.messages),
                static_cast<unsigned long long>(result.chunks));
  return 0;
}

int run_record(RecordCliOptions& options) {
  if (!options.recover.empty()) return run_recover(options.recover);
  const auto compression =
      mcap::compression_named(options.compression == "none" ? "" : options.compression);
  if (!compression)
    throw Error("--compression takes none, lz4 or zstd, not " + options.compression);
  options.record.compression = *compression;
  ns_of_seconds(options.record.duration_s, "--duration (0: until Ctrl-C)");
  if (!(options.buffer_mb >= 1.0 && options.buffer_mb <= 65536.0))
    throw Error("--buffer takes megabytes from 1 to 65536");
  options.record.buffer_bytes = static_cast<std::size_t>(options.buffer_mb * (1 << 20)) & ~7ull;
  set_realtime_options(options.realtime, options.record.loop);
  // States, commands and the world state come on the physics' step tape, a device's
  // updates on its driver's tape: each holds what a late reader missed, so the loop runs
  // under the normal scheduler, never taking a core from a physics, a controller or a
  // driver that runs under SCHED_FIFO (under SCHED_FIFO it put the example scene's step
  // p99 at 1.46x without the recorder; under the normal scheduler 0.92x,
  // bench/record_bench.sh).
  install_stop_signal_handlers();
  // Its lines on a pipe closed early (`afhub record 2>&1 | head`) are lost, not the file:
  // SIGPIPE ended the recorder there, the file cut off.
  std::signal(SIGPIPE, SIG_IGN);
  // A hub lost: the file is finished (the recorder's hook), and the process re-executes
  // to wait for the next hub and record into the next file: run.mcap, run.1.mcap, ...
  survive_hub_loss("afhub record");
  refuse_a_recording_there(options);
  // A re-attached recorder's --duration spans its files: what the hub's absence took
  // counts too (each file took the whole duration again: 7.6 s for --duration 4).
  options.record.duration_from_ns = carried_from_before_reattach();
  carry_into_reattach(options.record.duration_from_ns);
  const auto duration_over = [&] {
    if (options.record.duration_from_ns == 0 || options.record.duration_s <= 0.0 ||
        monotonic_ns() - options.record.duration_from_ns <
            static_cast<std::int64_t>(options.record.duration_s * 1e9))
      return false;
    std::fprintf(stderr, "afhub record: --duration %g s ended while the hub was away\n",
                 options.record.duration_s);
    return true;
  };
  if (duration_over()) return 0;
  const StartupWait wait(options.wait_s);
  wait.connect_to_hub("record");
  if (duration_over()) return 0;
  number_a_reattached_output(options);

  const bool live = isatty(STDERR_FILENO);
  double last_seconds = 0.0;
  std::uint64_t last_bytes = 0;
  const auto report = [&](const mcap::RecordProgress& p) {
    const double dt = p.seconds - last_seconds;
    const double rate = dt > 0.0 ? static_cast<double>(p.file_bytes - last_bytes) / 1e6 / dt : 0.0;
    last_seconds = p.seconds;
    last_bytes = p.file_bytes;
    if (live) std::fprintf(stderr, "\r%s\033[K", progress_line(p, rate).c_str());
  };
  // Said once the file is this recorder's: a second recorder on it is refused instead.
  const auto opened = [&] {
    std::fprintf(stderr, "afhub record: writing %s (Ctrl-C stops)\n",
                 options.record.output.c_str());
  };
  const mcap::RecordProgress end = mcap::record(
      options.record, [] { return !stop_requested(); }, report, opened);
  const double mean =
      end.seconds > 0.0 ? static_cast<double>(end.file_bytes) / 1e6 / end.seconds : 0;
  std::fprintf(stderr, "%safhub record: %s\n", live ? "\n" : "", progress_line(end, mean).c_str());
  if (end.dropped > 0)
    std::fprintf(stderr,
                 "afhub record: %llu messages were dropped: compressing and writing them did "
                 "not keep up (a larger --buffer absorbs a burst; a sustained rate needs most of "
                 "a free core for the recorder, a disk as fast, or fewer bodies: --bodies)\n",
                 static_cast<unsigned long long>(end.dropped));
  return 0;
}

}  // namespace

void register_record(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<RecordCliOptions>();
  auto* record = app.add_subcommand(
      "record",
      "Record body states, the world's state and the scene (and with options commands and "
      "devices) to an MCAP file at the rate they are published, until Ctrl-C or --duration; "
      "`afhub info` describes it, `afhub play` replays it.");
  record->add_option("-o,--output", options->record.output, "The MCAP file to write")
      ->capture_default_str();
  record->add_flag("--overwrite", options->overwrite,
                   "Record over the file -o names if it exists (by default that is refused)");
  record->add_option("--bodies", options->record.body_globs,
                     "Body channels to record, as globs on the full name or its end after a "
                     "'/' (arm/*, base; default: every body)");
  record->add_flag("--devices", options->record.devices, "Record every device's state and command");
  // The world's state is always recorded (play and replay need its clock); the flag is
  // taken so that a command line written with it runs.
  record->add_flag("--world")->description(
      "The world's state: always recorded, with or without this flag");
  record->add_flag("--commands", options->record.commands,
                   "Record the commands sent to the recorded bodies");
  record->add_option(
      "--duration", options->record.duration_s,
      "Seconds to record from the first message (or from the start, when none comes; "
      "default: until Ctrl-C)");
  record->add_option("--compression", options->compression, "Chunk compression: none, lz4 or zstd")
      ->capture_default_str();
  record
      ->add_option("--buffer", options->buffer_mb,
                   "Megabytes buffered between reading and the disk (a slower disk drops "
                   "messages, counted, when it is full)")
      ->capture_default_str();
  record->add_option("--profile", options->record.profile,
                     "ros2: a ROS 2 bag instead of afhub's payloads: each body's joint_states, "
                     "pose, twist and wrench, and /clock, CDR-encoded (stamps: simulation time)");
  record
      ->add_option("--recover", options->recover,
                   "Rewrite a file that was cut off (kill -9, a full disk) with its index; "
                   "no recording")
      ->check(CLI::ExistingFile);
  add_realtime_options(record, options->realtime, "the reading loop");
  record->add_option("--wait", options->wait_s,
                     "Started together with the hub (a launch script): wait up to this many "
                     "seconds for it, saying so once (default 0: fail at once)");
  record->callback([&selected, options] { selected = [options] { return run_record(*options); }; });
}

}  // namespace afhub::cli
