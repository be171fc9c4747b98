// `afhub ls`: the live bodies, with their publish rate, joints and owner.
#include <cstdio>
#include <memory>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "afhub/hub/json_writer.hpp"
#include "commands.hpp"
#include "format.hpp"

namespace afhub::cli {
namespace {

struct LsOptions {
  bool json = false;
};

int run_ls(const LsOptions& options) {
  connect_to_hub("ls", HubPolicy::kRequire);
  CatalogReader catalog;
  catalog.wait(std::chrono::milliseconds(1000));
  const BodyList& list = catalog.latest();
  if (options.json) {
    JsonWriter json;
    json.begin_array();
    for (std::uint32_t i = 0; i < list.body_count; ++i) {
      const BodyInfo& body = list.bodies[i];
      json.begin_object();
      json.key("body").value(name_of(body.channel));
      // null until the hub has measured the rate (its first seconds).
      json.key("rate_hz");
      if (rate_measured(body.publish_rate_hz))
        json.value(body.publish_rate_hz);
      else
        json.null();
      json.key("owner").value(name_of(body.owner));
      json.key("owner_pid").value(static_cast<long long>(body.owner_pid));
      json.key("joints").begin_array();
      for (std::uint32_t j = 0; j < body.joint_count; ++j) json.value(name_of(body.joint_names[j]));
      json.end_array().end_object();
    }
    json.end_array();
    std::printf("%s\n", json.str().c_str());
    return 0;
  }
  if (list.body_count == 0) {
    std::printf(
        "no bodies are published yet (start a simulation with `afhub run`, or `afhub synth`)\n");
    return 0;
  }
  std::printf("%-40s %10s %6s  %s\n", "BODY", "RATE_HZ", "JOINTS", "OWNER");
  for (std::uint32_t i = 0; i < list.body_count; ++i) {
    const BodyInfo& body = list.bodies[i];
    std::printf("%-40s %10s %6u  %s (pid %u)\n", std::string(name_of(body.channel)).c_str(),
                rate_text(body.publish_rate_hz).c_str(), body.joint_count,
                std::string(name_of(body.owner)).c_str(), body.owner_pid);
  }
  return 0;
}

}  // namespace

void register_ls(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<LsOptions>();
  auto* ls =
      app.add_subcommand("ls",
                         "List the live bodies: publish rate ('-' until the hub has measured it, "
                         "in a body's first seconds), joints and owner process.");
  ls->add_flag("--json", options->json, "Print a JSON array instead of a table.");
  ls->callback([&selected, options] { selected = [options] { return run_ls(*options); }; });
}

}  // namespace afhub::cli
