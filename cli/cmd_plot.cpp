// `afhub plot FILE.mcap BODY`: a body's recorded fields over time, with gnuplot.
#include <cstdio>
#include <memory>

#include "afhub/record/plot.hpp"
#include "commands.hpp"

namespace afhub::cli {

void register_plot(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<mcap::PlotOptions>();
  auto* plot = app.add_subcommand(
      "plot",
      "Plot a body's recorded fields over simulated time with gnuplot: to a .png or .svg "
      "file, or as text in the terminal.");
  plot->add_option("file", options->file, "The .mcap file")->required()->check(CLI::ExistingFile);
  plot->add_option("body", options->body, "Body channel name or a unique suffix of it, e.g. 'base'")
      ->required();
  plot->add_option(
          "--fields", options->fields,
          std::string("Panels, comma-separated: ") + mcap::kPlotFields + " (default: joints)")
      ->delimiter(',');
  plot->add_option("--out,-o", options->out, "A .png or .svg file (default: text on stdout)");
  plot->callback([&selected, options] {
    selected = [options] {
      const mcap::PlotReport report = mcap::plot(*options);
      if (!options->out.empty())
        std::printf("wrote %s: %zu states\n", options->out.c_str(), report.states);
      if (!report.cut_off.empty())
        std::fprintf(stderr,
                     "afhub plot: warning: %s was cut off (%s): plotted up to there; `afhub "
                     "record --recover` gives it its index\n",
                     options->file.c_str(), report.cut_off.c_str());
      return 0;
    };
  });
}

}  // namespace afhub::cli
