// The physics' step log (see step_log.hpp).
#include "afhub/bench/step_log.hpp"

#include <algorithm>
#include <fstream>

#include "afhub/shm_layout/error.hpp"
#include "text_format.hpp"

namespace afhub::bench {

std::vector<LoggedStep> read_step_log(const std::string& path, std::int64_t from_ns,
                                      std::int64_t to_ns) {
  std::ifstream in(path);
  std::string header;
  if (!std::getline(in, header) || header != "begin_ns step_us commands_us publish_us due_ns late")
    throw Error("the physics wrote no step log to " + path + " (its first line: \"" + header +
                "\")");
  std::vector<LoggedStep> steps;
  long long begin = 0, due = 0;
  float step = 0, commands = 0, publish = 0;
  unsigned late = 0;
  while (in >> begin >> step >> commands >> publish >> due >> late)
    if (begin >= from_ns && begin <= to_ns)
      steps.push_back({begin, due, {commands, step - publish, publish}, late});
  return steps;
}

LateCommands late_commands(std::span<const LoggedStep> steps) {
  LateCommands counted;
  bool previous_behind = false;
  std::int64_t previous_end_ns = 0;
  for (const LoggedStep& step : steps) {
    // Its commands are read before it begins, once the physics is awake.
    const auto woke_ns = step.begin_ns - static_cast<std::int64_t>(step.phases.commands * 1e3F);
    const bool behind = step.due_ns > 0 && woke_ns - step.due_ns > kBehindNs;
    counted.late += step.late;
    if (behind || previous_behind)
      counted.behind += step.late;
    else
      ++counted.on_grid_steps;
    if (behind && !previous_behind) {
      ++counted.falls;
      if (woke_ns - std::max(step.due_ns, previous_end_ns) > kBehindNs) ++counted.woke_late;
    }
    previous_behind = behind;
    previous_end_ns = step.begin_ns +
                      static_cast<std::int64_t>((step.phases.physics + step.phases.publish) * 1e3F);
  }
  return counted;
}

std::string late_commands_text(const LateCommands& late, int bodies) {
  if (late.late == 0) return "";
  std::string text =
      format(
          "  %.0f late by the physics' step log: %.0f at a step it began over %.1f ms behind "
          "its grid, or the step after",
          static_cast<double>(late.late), static_cast<double>(late.behind),
          static_cast<double>(kBehindNs) * 1e-6) +
      format(" (it fell behind %.0f times, %.0f of them waking up late: the machine held it)",
             static_cast<double>(late.falls), static_cast<double>(late.woke_late));
  const double on_grid = static_cast<double>(late.on_grid_steps) * bodies;
  if (on_grid > 0)
    text += format("; at the other %.0f steps, %.2f %% in time",
                   static_cast<double>(late.on_grid_steps),
                   100.0 * (1.0 - static_cast<double>(late.late - late.behind) / on_grid));
  return text + "\n";
}

}  // namespace afhub::bench
