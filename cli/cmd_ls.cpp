// `afhub ls`: the live bodies, with their publish rate, joints and owner.
#include <cstdio>
#include <memory>

#include "afhub/hub/bodies.hpp"
#include "afhub/hub/hub_presence.hpp"
#include "commands.hpp"
#include "listings.hpp"

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
  if (options.json)
    std::printf("%s\n", ls_json(list).c_str());
  else
    std::printf("%s", ls_text(list).c_str());
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
