// `afhub info FILE.mcap`: what a recording holds: duration, channels with their message
// counts, rates and gaps, its metadata; and whether it was cut off.
#include <cstdio>
#include <memory>

#include "afhub/hub/json_writer.hpp"
#include "afhub/record/file_summary.hpp"
#include "commands.hpp"

namespace afhub::cli {
namespace {

struct InfoOptions {
  std::string file;
  bool json = false;
};

void print_json(const mcap::FileSummary& s) {
  JsonWriter json;
  json.begin_object();
  json.key("file").value(s.path);
  json.key("profile").value(s.profile);
  json.key("library").value(s.library);
  json.key("complete").value(s.complete);
  json.key("cut_off").value(s.cut_off);
  json.key("file_bytes").value(static_cast<unsigned long long>(s.file_bytes));
  json.key("chunks").value(static_cast<unsigned long long>(s.chunks));
  json.key("compression").begin_array();
  for (const auto& c : s.compressions) json.value(c);
  json.end_array();
  json.key("messages").value(static_cast<unsigned long long>(s.messages));
  json.key("duration_s").value(s.duration_s());
  json.key("start_ns").value(static_cast<unsigned long long>(s.first_ns));
  json.key("metadata").begin_array();  // records may repeat a name (a physics restarted)
  for (const auto& [name, entries] : s.metadata) {
    json.begin_object().key("name").value(name).key("entries").begin_object();
    for (const auto& [key, value] : entries) json.key(key).value(value);
    json.end_object().end_object();
  }
  json.end_array();
  json.key("channels").begin_array();
  for (const auto& c : s.channels) {
    json.begin_object();
    json.key("topic").value(c.topic);
    json.key("schema").value(c.schema);
    json.key("encoding").value(c.encoding);
    json.key("messages").value(static_cast<unsigned long long>(c.messages));
    json.key("rate_hz").value(c.rate_hz());
    json.key("gaps").value(static_cast<unsigned long long>(c.gaps));
    json.key("skipped").value(static_cast<unsigned long long>(c.skipped));
    json.key("first_ns").value(static_cast<unsigned long long>(c.first_ns));
    json.key("last_ns").value(static_cast<unsigned long long>(c.last_ns));
    json.end_object();
  }
  json.end_array();
  json.end_object();
  std::printf("%s\n", json.str().c_str());
}

void print_text(const mcap::FileSummary& s) {
  std::string compressions;
  for (const auto& c : s.compressions) compressions += (compressions.empty() ? "" : ", ") + c;
  std::printf("file:        %s (%.1f MB, %llu chunks, %s)\n", s.path.c_str(),
              static_cast<double>(s.file_bytes) / 1e6, static_cast<unsigned long long>(s.chunks),
              compressions.empty() ? "no chunks" : compressions.c_str());
  std::printf("written by:  %s%s%s\n", s.library.c_str(), s.profile.empty() ? "" : ", profile ",
              s.profile.c_str());
  std::printf("duration:    %.3f s\n", s.duration_s());
  std::printf("messages:    %llu\n", static_cast<unsigned long long>(s.messages));
  for (const auto& [name, entries] : s.metadata) {
    std::printf("metadata %s:\n", name.c_str());
    for (const auto& [key, value] : entries)
      std::printf("  %-12s %s\n", key.c_str(), value.c_str());
  }
  std::printf("channels:    %zu\n", s.channels.size());
  std::printf("  %-44s %-20s %10s %10s %6s\n", "topic", "schema", "messages", "rate Hz", "gaps");
  for (const auto& c : s.channels)
    std::printf("  %-44s %-20s %10llu %10.1f %6llu\n", c.topic.c_str(), c.schema.c_str(),
                static_cast<unsigned long long>(c.messages), c.rate_hz(),
                static_cast<unsigned long long>(c.gaps));
  if (!s.complete)
    std::printf(
        "cut off:     %s. Everything before it is above; `afhub record --recover %s` "
        "rewrites the file with its index.\n",
        s.cut_off.c_str(), s.path.c_str());
}

}  // namespace

void register_info(CLI::App& app, Runner& selected) {
  auto options = std::make_shared<InfoOptions>();
  auto* info = app.add_subcommand(
      "info",
      "Describe an MCAP recording: duration, channels, message counts, rates, gaps, "
      "metadata, and whether it was cut off.");
  info->add_option("file", options->file, "The .mcap file")->required()->check(CLI::ExistingFile);
  info->add_flag("--json", options->json, "One JSON object");
  info->callback([&selected, options] {
    selected = [options] {
      const mcap::FileSummary summary = mcap::summarize(options->file);
      options->json ? print_json(summary) : print_text(summary);
      return 0;
    };
  });
}

}  // namespace afhub::cli
