#include "afhub/record/file_summary.hpp"

#include <algorithm>
#include <filesystem>
#include <map>

#include "afhub/shm_layout/error.hpp"

namespace afhub::mcap {

double ChannelSummary::rate_hz() const {
  return messages > 1 && last_ns > first_ns
             ? static_cast<double>(messages - 1) * 1e9 / static_cast<double>(last_ns - first_ns)
             : 0.0;
}

double FileSummary::duration_s() const {
  return last_ns > first_ns ? static_cast<double>(last_ns - first_ns) * 1e-9 : 0.0;
}

namespace {

class Summarizer : public Visitor {
 public:
  explicit Summarizer(FileSummary& out) : out_(out) {}

  void header(const std::string& profile, const std::string& library) override {
    out_.profile = profile;
    out_.library = library;
  }
  void schema(const Schema& schema) override { schemas_[schema.id] = schema.name; }
  void channel(const Channel& channel) override {
    if (index_.count(channel.id)) return;  // repeated (a recovered file's summary, or chunks)
    ChannelSummary summary;
    summary.topic = channel.topic;
    summary.encoding = channel.message_encoding;
    const auto schema = schemas_.find(channel.schema_id);
    summary.schema = schema == schemas_.end() ? "" : schema->second;
    summary.metadata = channel.metadata;
    index_[channel.id] = {out_.channels.size(), 0};
    out_.channels.push_back(std::move(summary));
  }
  void metadata(const std::string& name, const Metadata& metadata) override {
    out_.metadata.emplace_back(name, metadata);
  }
  void chunk(std::string_view compression) override {
    const std::string name = compression.empty() ? "none" : std::string(compression);
    if (std::find(out_.compressions.begin(), out_.compressions.end(), name) ==
        out_.compressions.end())
      out_.compressions.push_back(name);
  }
  void message(const Message& message) override {
    const auto found = index_.find(message.channel_id);
    if (found == index_.end())
      throw Error(out_.path + ": a message on channel " + std::to_string(message.channel_id) +
                  ", which no channel record declares (a corrupt file)");
    auto& [at, last_sequence] = found->second;
    ChannelSummary& channel = out_.channels[at];
    if (channel.messages == 0) {
      channel.first_ns = message.log_time_ns;
    } else if (message.sequence != last_sequence + 1) {
      ++channel.gaps;
      if (message.sequence > last_sequence) channel.skipped += message.sequence - last_sequence - 1;
    }
    last_sequence = message.sequence;
    channel.last_ns = std::max(channel.last_ns, message.log_time_ns);
    ++channel.messages;
    if (out_.messages == 0) out_.first_ns = message.log_time_ns;
    out_.first_ns = std::min(out_.first_ns, message.log_time_ns);
    out_.last_ns = std::max(out_.last_ns, message.log_time_ns);
    ++out_.messages;
  }

 private:
  FileSummary& out_;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, std::pair<std::size_t, std::uint32_t>> index_;  // at, last sequence
};

}  // namespace

FileSummary summarize(const std::string& path) {
  FileSummary summary;
  summary.path = path;
  Summarizer summarizer(summary);
  const ScanResult result = scan(path, summarizer);
  summary.complete = result.complete;
  summary.cut_off = result.cut_off;
  summary.chunks = result.chunks;
  std::error_code error;
  summary.file_bytes = std::filesystem::file_size(path, error);
  return summary;
}

}  // namespace afhub::mcap
