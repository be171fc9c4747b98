// Headless Chromium over the DevTools protocol (see devtools_client.hpp).
#include "devtools_client.hpp"

#include <civetweb.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "afhub/rt/process_spawn.hpp"
#include "afhub/shm_layout/error.hpp"
#include "afhub_process.hpp"
#include "web_client.hpp"

namespace afhub::test {
namespace {

constexpr auto kAnswerTimeout = std::chrono::seconds(60);

int on_data(mg_connection*, int flags, char* data, size_t length, void* browser) {
  if ((flags & 0x0f) == MG_WEBSOCKET_OPCODE_TEXT)
    static_cast<Browser*>(browser)->on_message(data, length);
  return 1;
}

void on_close(const mg_connection*, void*) {}

std::vector<std::uint8_t> base64_decode(const std::string& text) {
  std::vector<std::uint8_t> out;
  std::uint32_t bits = 0;
  int count = 0;
  for (char c : text) {
    int v = -1;
    if (c >= 'A' && c <= 'Z') v = c - 'A';
    if (c >= 'a' && c <= 'z') v = c - 'a' + 26;
    if (c >= '0' && c <= '9') v = c - '0' + 52;
    if (c == '+') v = 62;
    if (c == '/') v = 63;
    if (v < 0) continue;  // '=' padding
    bits = (bits << 6) | static_cast<std::uint32_t>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<std::uint8_t>((bits >> count) & 0xff));
    }
  }
  return out;
}

}  // namespace

std::string json_quote(const std::string& text) {
  return nlohmann::json(text).dump();
}

Browser::Browser(const std::string& dir) {
  const std::string profile = dir + "/chromium-profile";
  std::filesystem::remove_all(profile);
  SpawnOptions options;
  options.search_path = true;
  options.own_process_group = true;  // its renderer and GPU processes stop with it
  options.output_path = dir + "/chromium.log";
  try {
    pid_ = spawn_process({"chromium", "--headless=new", "--no-sandbox", "--use-gl=swiftshader",
                          "--enable-unsafe-swiftshader", "--window-size=800,600", "--no-first-run",
                          "--remote-debugging-port=0", "--user-data-dir=" + profile, "about:blank"},
                         options);
  } catch (const Error& error) {
    problem_ = error.what();
    return;
  }
  // Chromium writes the port it chose, and its browser target's path, when it listens.
  int port = 0;
  wait_until(
      [&] {
        std::ifstream(profile + "/DevToolsActivePort") >> port;
        return port > 0;
      },
      std::chrono::seconds(60));
  if (port <= 0) {
    problem_ = "chromium did not open its DevTools port: " + read_file(dir + "/chromium.log");
    return;
  }
  // The page target's WebSocket path, from /json/list.
  std::string path;
  HttpReply list;
  wait_until(
      [&] {
        list = http_request(port, "GET", "/json/list");
        if (list.status != 200) return false;
        // The page chromium opened; its URL's host is what the request's Host header
        // said, so only its path is taken.
        const nlohmann::json targets = parse_json(list.body);
        const nlohmann::json* page = find_element(targets, "type", "page");
        if (!page || !page->contains("webSocketDebuggerUrl")) return false;
        const std::string url = page->at("webSocketDebuggerUrl").get<std::string>();
        const std::size_t start = url.find("/devtools/page/");
        if (start == std::string::npos) return false;
        path = url.substr(start);
        return true;
      },
      std::chrono::seconds(20));
  if (path.empty()) {
    problem_ = "chromium listed no page target on port " + std::to_string(port) + ": " +
               std::to_string(list.status) + " " + list.body;
    return;
  }
  mg_init_library(0);
  library_ = true;
  char error[256] = "";
  connection_ = mg_connect_websocket_client("127.0.0.1", port, 0, error, sizeof error, path.c_str(),
                                            nullptr, on_data, on_close, this);
  if (!connection_) {
    problem_ = std::string("cannot connect to chromium's page target: ") + error;
    return;
  }
  for (const char* domain : {"Page.enable", "Runtime.enable", "Log.enable"})
    if (call(domain, "{}").is_null()) {
      problem_ = std::string(domain) + " got no answer";
      mg_close_connection(connection_);
      connection_ = nullptr;
      return;
    }
}

Browser::~Browser() {
  if (connection_) mg_close_connection(connection_);
  if (library_) mg_exit_library();
  if (pid_ > 0) {
    kill(-pid_, SIGTERM);
    int status = 0;
    if (!wait_until([&] { return waitpid(pid_, &status, WNOHANG) == pid_; },
                    std::chrono::seconds(10))) {
      kill(-pid_, SIGKILL);
      waitpid(pid_, &status, 0);
    }
    kill(-pid_, SIGKILL);  // any helper process left in its group
  }
}

void Browser::on_message(const char* data, std::size_t length) {
  const std::string text(data, length);
  nlohmann::json message;
  try {
    message = parse_json(text);
  } catch (const std::exception&) {
    return;
  }
  std::lock_guard lock(mutex_);
  if (message.contains("id")) {
    answers_[message.at("id").get<int>()] = text;
    answered_.notify_all();
    return;
  }
  if (!message.contains("method")) return;
  const std::string method = message.at("method").get<std::string>();
  if (method == "Page.loadEventFired") {
    loaded_ = true;
    answered_.notify_all();
  } else if (method == "Runtime.consoleAPICalled" || method == "Runtime.exceptionThrown" ||
             method == "Log.entryAdded") {
    console_.push_back(method + ": " + text);
  }
}

nlohmann::json Browser::call(const std::string& method, const std::string& params_json) {
  if (!connection_) return {};
  int id = 0;
  {
    std::lock_guard lock(mutex_);
    id = next_id_++;
  }
  const std::string request = "{\"id\":" + std::to_string(id) + ",\"method\":\"" + method +
                              "\",\"params\":" + params_json + "}";
  mg_websocket_client_write(connection_, MG_WEBSOCKET_OPCODE_TEXT, request.data(), request.size());
  std::unique_lock lock(mutex_);
  if (!answered_.wait_for(lock, kAnswerTimeout, [&] { return answers_.count(id) != 0; })) {
    problem_ = method + ": no answer from chromium";
    return {};
  }
  const nlohmann::json answer = parse_json(answers_[id]);
  answers_.erase(id);
  if (!answer.contains("result")) {
    problem_ =
        method + ": " +
        (answer.contains("error") ? answer.at("error").at("message").get<std::string>() : "");
    return {};
  }
  return answer.at("result");
}

bool Browser::navigate(const std::string& url) {
  {
    std::lock_guard lock(mutex_);
    loaded_ = false;
  }
  if (call("Page.navigate", "{\"url\":" + json_quote(url) + "}").is_null()) return false;
  std::unique_lock lock(mutex_);
  return answered_.wait_for(lock, kAnswerTimeout, [&] { return loaded_; });
}

nlohmann::json Browser::evaluate(const std::string& expression) {
  const nlohmann::json result =
      call("Runtime.evaluate", "{\"expression\":" + json_quote(expression) +
                                   ",\"returnByValue\":true,\"awaitPromise\":true}");
  if (result.is_null()) return {};
  if (result.contains("exceptionDetails")) {
    const nlohmann::json& details = result.at("exceptionDetails");
    problem_ = expression + " threw: " +
               (details.contains("exception") && details.at("exception").contains("description")
                    ? details.at("exception").at("description").get<std::string>()
                    : details.at("text").get<std::string>());
    return {};
  }
  const nlohmann::json& value = result.at("result");
  return value.contains("value") ? value.at("value") : nlohmann::json();
}

void Browser::click(double x, double y) {
  for (const char* type : {"mousePressed", "mouseReleased"}) {
    std::ostringstream params;
    params << "{\"type\":\"" << type << "\",\"x\":" << x << ",\"y\":" << y
           << ",\"button\":\"left\",\"clickCount\":1}";
    call("Input.dispatchMouseEvent", params.str());
  }
}

bool Browser::screenshot(const std::string& path) {
  const nlohmann::json result = call("Page.captureScreenshot", R"({"format":"png"})");
  if (result.is_null()) return false;
  const std::vector<std::uint8_t> png = base64_decode(result.at("data").get<std::string>());
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  return !png.empty();
}

std::vector<std::string> Browser::console() {
  std::lock_guard lock(mutex_);
  return console_;
}

void Browser::clear_console() {
  std::lock_guard lock(mutex_);
  console_.clear();
}

}  // namespace afhub::test
