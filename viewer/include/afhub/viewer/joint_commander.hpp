// The page's joint sliders (`afhub view --allow-commands`): a request
// "body=CHANNEL&joint=INDEX&value=V" sends one position command to the body, the
// named joint to V and its other joints held where they are. A command is sent
// once; the page repeats it while the slider moves, and the physics' watchdog
// releases the joints when it stops. Called from the server's threads.
#pragma once

#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "afhub/hub/bodies.hpp"

namespace afhub::viewer {

class JointCommander {
 public:
  // Returns "" when the command was sent, else what is wrong with the request.
  std::string run(const std::string& query);

 private:
  std::mutex mutex_;
  std::map<std::string, std::unique_ptr<BodyClient>> clients_;
};

}  // namespace afhub::viewer
