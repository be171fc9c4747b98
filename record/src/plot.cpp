#include "afhub/record/plot.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>

#include "afhub/record/mcap_reader.hpp"
#include "afhub/shm_layout/body_state.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub/shm_layout/payload_check.hpp"
#include "recorded_payloads.hpp"

extern char** environ;

namespace afhub::mcap {

namespace {

// One panel: its title, unit, and the named series it draws from a state.
struct Panel {
  std::string title, unit;
  std::vector<std::string> names;
  std::function<void(const BodyState&, std::vector<double>&)> values;
};

Panel vectors_panel(const std::string& title, const std::string& unit,
                    std::vector<std::string> names,
                    std::function<std::vector<const Vec3*>(const BodyState&)> vectors) {
  return {title, unit, std::move(names), [vectors](const BodyState& s, std::vector<double>& out) {
            for (const Vec3* v : vectors(s)) out.insert(out.end(), {v->x, v->y, v->z});
          }};
}

Panel panel_of(const std::string& field, const std::vector<std::string>& joints) {
  const auto joint_panel = [&](const std::string& title, const std::string& unit,
                               double JointSample::*member) {
    return Panel{title, unit, joints, [member, n = joints.size()](const BodyState& s, auto& out) {
                   for (std::size_t j = 0; j < n; ++j)
                     out.push_back(j < s.joint_count ? s.joints[j].*member : 0.0);
                 }};
  };
  if (field == "joints") return joint_panel("joint positions", "rad or m", &JointSample::position);
  if (field == "velocities")
    return joint_panel("joint velocities", "rad/s or m/s", &JointSample::velocity);
  if (field == "efforts") return joint_panel("joint efforts", "N m or N", &JointSample::effort);
  if (field == "pose")
    return vectors_panel("position", "m", {"x", "y", "z"},
                         [](const BodyState& s) { return std::vector{&s.pose.position_m}; });
  if (field == "twist")
    return vectors_panel("twist", "m/s, rad/s", {"vx", "vy", "vz", "wx", "wy", "wz"},
                         [](const BodyState& s) {
                           return std::vector{&s.twist.linear_mps, &s.twist.angular_radps};
                         });
  if (field == "wrench")
    return vectors_panel("wrench applied", "N, N m", {"fx", "fy", "fz", "tx", "ty", "tz"},
                         [](const BodyState& s) {
                           return std::vector{&s.wrench.force_n, &s.wrench.torque_nm};
                         });
  throw Error("--fields: no field '" + field + "'; plot takes " + kPlotFields);
}

// The body's states, as rows of simulated time and each panel's values. The body is
// the one whose channel matches, wherever in the file it first appears.
class Series : public Visitor {
 public:
  explicit Series(const PlotOptions& options) : options_(options) {}

  void header(const std::string& profile, const std::string&) override {
    if (!profile.empty())
      throw Error(options_.file + " was recorded with --profile " + profile +
                  ": `afhub plot` plots afhub's own recordings (no --profile); ROS 2 tools "
                  "read this one");
  }

  void channel(const Channel& channel) override {
    const auto instance = channel.metadata.find("afhub_instance");
    if (instance == channel.metadata.end() || !channel.topic.ends_with("/state") ||
        !channel.metadata.count("joint_names"))
      return;
    const std::string& name = instance->second;
    bodies_ += (bodies_.empty() ? "" : ", ") + name;
    if (name != options_.body && !name.ends_with("/" + options_.body)) return;
    if (!body.empty() && name != body) ambiguous_ = true;
    if (!body.empty()) return;
    body = name;
    channel_id_ = channel.id;
    const std::vector<std::string> joints = joint_names_in(channel.metadata);
    for (const std::string& field : options_.fields) panels.push_back(panel_of(field, joints));
  }
  void message(const Message& message) override {
    if (body.empty() || message.channel_id != channel_id_) return;
    const auto state = checked_copy(message.data, PayloadKind::kBodyState, aligned_,
                                    options_.file + ": a state of " + body);
    std::memcpy(&state_, state.data(), std::min(state.size(), sizeof state_));
    std::vector<double>& row = rows.emplace_back();
    row.push_back(state_.header.sim_time_s);
    for (const Panel& panel : panels) panel.values(state_, row);
  }
  // Throws afhub::Error when no body, or several, answered to the name.
  void require_one() const {
    if (body.empty() || ambiguous_)
      throw Error(options_.file +
                  (body.empty() ? " records no body named '" : " records several bodies named '") +
                  options_.body + "'; it records " + (bodies_.empty() ? "none" : bodies_));
  }

  std::string body;
  std::vector<Panel> panels;
  std::vector<std::vector<double>> rows;

 private:
  const PlotOptions& options_;
  std::string bodies_;  // every body recorded, for the error
  bool ambiguous_ = false;
  std::uint16_t channel_id_ = 0;
  std::vector<std::uint64_t> aligned_;
  BodyState state_;
};

// gnuplot's single-quoted string: a quote is doubled.
std::string quoted(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

void run_gnuplot(const std::string& script, const std::string& log) {
  if (access("/usr/bin/gnuplot", X_OK) != 0)
    throw Error("afhub plot needs gnuplot: install Debian's gnuplot-nox");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  const char* argv[] = {"gnuplot", script.c_str(), nullptr};
  pid_t pid = 0;
  const int error = posix_spawn(&pid, "/usr/bin/gnuplot", &actions, nullptr,
                                const_cast<char* const*>(argv), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) throw Error(std::string("cannot start gnuplot: ") + std::strerror(error));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::ifstream in(log);
    const std::string said((std::istreambuf_iterator<char>(in)), {});
    throw Error("gnuplot failed: " + said);
  }
}

}  // namespace

PlotReport plot(const PlotOptions& options) {
  if (options.fields.empty()) throw Error(std::string("--fields: name one of ") + kPlotFields);
  for (const std::string& field : options.fields) panel_of(field, {});  // checked before reading
  const std::string extension = std::filesystem::path(options.out).extension().string();
  if (!options.out.empty() && extension != ".png" && extension != ".svg")
    throw Error("--out " + options.out + ": plot writes .png or .svg files");
  Series series(options);
  const ScanResult scanned = scan(options.file, series);
  series.require_one();
  if (series.rows.empty()) throw Error(options.file + " holds no state of " + series.body);

  char folder[] = "/tmp/afhub-plot-XXXXXX";
  if (!mkdtemp(folder)) throw Error("cannot make a folder for the plot's data in /tmp");
  const std::string dir = folder;
  {
    std::ofstream data(dir + "/states.dat");
    data.precision(9);
    for (const auto& row : series.rows) {
      for (std::size_t i = 0; i < row.size(); ++i) data << (i ? " " : "") << row[i];
      data << "\n";
    }
    std::ofstream script(dir + "/plot.gp");
    const std::size_t panels = series.panels.size();
    if (options.out.empty())
      script << "set terminal dumb size 100," << 24 * panels << "\n";
    else
      script << "set terminal " << (extension == ".png" ? "pngcairo" : "svg") << " size 1200,"
             << 360 * panels << " font ',10'\n"
             << "set output " << quoted(options.out) << "\n";
    script << "set multiplot layout " << panels << ",1 title " << quoted(series.body) << "\n"
           << "set grid\nset key outside right\nset xlabel 'simulated time (s)'\n";
    std::size_t column = 2;
    for (const Panel& panel : series.panels) {
      script << "set title " << quoted(panel.title) << "\nset ylabel " << quoted(panel.unit)
             << "\nplot ";
      for (std::size_t i = 0; i < panel.names.size(); ++i)
        script << (i ? ", " : "") << quoted(dir + "/states.dat") << " using 1:" << column++
               << " with lines title " << quoted(panel.names[i]);
      script << "\n";
    }
    script << "unset multiplot\n";
  }
  try {
    run_gnuplot(dir + "/plot.gp", dir + "/gnuplot.log");
  } catch (...) {
    std::filesystem::remove_all(dir);
    throw;
  }
  std::filesystem::remove_all(dir);
  return {series.rows.size(), scanned.cut_off};
}

}  // namespace afhub::mcap
