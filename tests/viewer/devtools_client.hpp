// Headless Chromium (Debian's chromium) driven over the DevTools protocol: the test
// starts it with --remote-debugging-port=0, reads the port it chose from its profile's
// DevToolsActivePort file, and talks to its page target over civetweb's WebSocket
// client: navigate, evaluate JavaScript in the page, click, take screenshots.
#pragma once

#include <sys/types.h>

#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "strict_json.hpp"

struct mg_connection;

namespace afhub::test {

class Browser {
 public:
  // Starts chromium with its profile under `dir`; check ready().
  explicit Browser(const std::string& dir);
  ~Browser();
  Browser(const Browser&) = delete;
  Browser& operator=(const Browser&) = delete;

  bool ready() const { return connection_ != nullptr; }
  const std::string& problem() const { return problem_; }

  // Loads `url` and waits until its load event.
  bool navigate(const std::string& url);
  // Runs `expression` in the page (promises awaited); returns its value (by value),
  // or null with problem() set when it threw.
  nlohmann::json evaluate(const std::string& expression);
  // A left click at the page's CSS pixel (x, y).
  void click(double x, double y);
  // The page as a PNG file at `path`.
  bool screenshot(const std::string& path);
  // Console messages and uncaught exceptions the page reported so far.
  std::vector<std::string> console();
  void clear_console();

  void on_message(const char* data, std::size_t length);

 private:
  // Sends one command and waits for its answer's "result" (null on error or timeout).
  nlohmann::json call(const std::string& method, const std::string& params_json);

  pid_t pid_ = -1;
  mg_connection* connection_ = nullptr;
  bool library_ = false;  // civetweb's library initialised: exit it too
  std::string problem_;
  int next_id_ = 1;
  std::mutex mutex_;
  std::condition_variable answered_;
  std::map<int, std::string> answers_;
  std::vector<std::string> console_;
  bool loaded_ = false;
};

// A JSON string literal of `text` (for building protocol parameters).
std::string json_quote(const std::string& text);

}  // namespace afhub::test
