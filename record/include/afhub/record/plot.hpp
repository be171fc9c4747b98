// `afhub plot`: a body's recorded fields over simulated time, drawn by gnuplot: a panel
// per field group (joint positions, velocities, efforts, position, twist, wrench), to a
// PNG or SVG file, or as text in the terminal.
#pragma once

#include <string>
#include <vector>

namespace afhub::mcap {

// The field groups `afhub plot --fields` takes.
inline constexpr const char* kPlotFields = "joints, velocities, efforts, pose, twist, wrench";

struct PlotOptions {
  std::string file;
  std::string body;  // a body channel or a unique suffix ("link3")
  std::vector<std::string> fields{"joints"};
  std::string out;  // .png or .svg; "": text on stdout
};

struct PlotReport {
  std::size_t states = 0;  // plotted
  std::string cut_off;     // the file was cut off there, and plotted up to it ("": not cut)
};

// Throws afhub::Error for a body the file does not hold, an unknown field, a file that
// cannot be read, or gnuplot missing or failing.
PlotReport plot(const PlotOptions& options);

}  // namespace afhub::mcap
