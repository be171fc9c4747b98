// ROS 1 topics through roscpp, the transport AMBF uses: TCPROS on loopback with
// TCP_NODELAY, std_msgs/UInt8MultiArray carrying the stamps in its first bytes.
// The bench starts its own rosmaster and sets ROS_MASTER_URI for both processes.
// Messages arrive through roscpp's receive thread into the callback queue, which
// the receiver waits on, as ros::spin does.
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <std_msgs/UInt8MultiArray.h>

#include <cstring>

#include "afhub/shm_layout/error.hpp"
#include "transport.hpp"

namespace afhub::bench {
namespace {

class Ros1Transport : public Transport {
 public:
  Ros1Transport(Side side, const std::string& session) {
    const std::string base = "/afhub_bench_" + session;
    const bool ping = side == Side::kPing;
    publisher_ = node_.advertise<std_msgs::UInt8MultiArray>(base + (ping ? "/ping" : "/pong"), 1);
    subscriber_ = node_.subscribe(base + (ping ? "/pong" : "/ping"), 1, &Ros1Transport::on_message,
                                  this, ros::TransportHints().tcpNoDelay());
    message_.data.resize(kMaxPayloadBytes);
  }

  std::int64_t send(std::uint32_t bytes, std::uint64_t round,
                    std::int64_t peer_receive_ns) override {
    // The layout (8 bytes) and the array length (4) come first: the message is `bytes` long.
    message_.data.resize(bytes - kOverheadBytes);
    const Stamps stamps{round, monotonic_ns(), peer_receive_ns};
    std::memcpy(message_.data.data(), &stamps, sizeof stamps);
    touch_written(reinterpret_cast<char*>(message_.data.data()) + sizeof stamps,
                  message_.data.size() - sizeof stamps, round);
    publisher_.publish(message_);
    return stamps.send_ns;
  }

  std::optional<Message> receive(std::int64_t deadline_ns) override {
    while (!received_) {
      const std::int64_t left = deadline_ns - monotonic_ns();
      if (left <= 0 || !ros::ok()) return std::nullopt;
      ros::getGlobalCallbackQueue()->callAvailable(
          ros::WallDuration(0, static_cast<int>(std::min<std::int64_t>(left, 100'000'000))));
    }
    std::optional<Message> message = received_;
    received_.reset();
    return message;
  }

 private:
  static constexpr std::uint32_t kOverheadBytes = 12;

  void on_message(const std_msgs::UInt8MultiArray::ConstPtr& incoming) {
    if (incoming->data.size() < sizeof(Stamps)) return;
    Stamps stamps;
    std::memcpy(&stamps, incoming->data.data(), sizeof stamps);
    touch_read(reinterpret_cast<const char*>(incoming->data.data()) + sizeof stamps,
               incoming->data.size() - sizeof stamps, stamps.round, "ros1");
    received_ = Message{static_cast<std::uint32_t>(incoming->data.size() + kOverheadBytes),
                        stamps.round, stamps.send_ns, stamps.peer_receive_ns, monotonic_ns()};
  }

  ros::NodeHandle node_;
  ros::Publisher publisher_;
  ros::Subscriber subscriber_;
  std_msgs::UInt8MultiArray message_;
  std::optional<Message> received_;
};

}  // namespace

std::unique_ptr<Transport> open_ros1_transport(Side side, const std::string& session) {
  if (!ros::isInitialized()) {
    int argc = 0;
    ros::init(argc, nullptr, side == Side::kPing ? "afhub_bench" : "afhub_bench_peer",
              ros::init_options::NoSigintHandler | ros::init_options::AnonymousName |
                  ros::init_options::NoRosout);
    const std::int64_t give_up = monotonic_ns() + 10'000'000'000;
    while (!ros::master::check()) {
      if (monotonic_ns() > give_up)
        throw Error("ros1: no rosmaster at " + ros::master::getURI() + " after 10 s");
      usleep(50'000);
    }
  }
  return std::make_unique<Ros1Transport>(side, session);
}

}  // namespace afhub::bench
