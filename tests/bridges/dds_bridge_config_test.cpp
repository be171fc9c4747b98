// `afhub bridge dds --config FILE`: every setting is read; unknown keys and bad values
// are refused with the file, line and column and what to write instead.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "afhub/bridges/dds_bridge_config.hpp"
#include "afhub/shm_layout/error.hpp"
#include "model_files.hpp"

namespace afhub::bridges {
namespace {

// The message of the error reading `text` as a config, or "" when it reads.
std::string error_of(const std::string& text) {
  afhub::testing::ModelFolder folder;
  const std::string path = folder.write("bridge.yaml", text);
  try {
    read_dds_bridge_config(path);
  } catch (const Error& error) {
    return std::string(error.what()).substr(path.size());  // from ":line:column"
  }
  return "";
}

TEST(DdsBridgeConfig, ReadsEverySetting) {
  afhub::testing::ModelFolder folder;
  const std::string path = folder.write("bridge.yaml",
                                        "domain: 7\n"
                                        "interface: veth0\n"
                                        "export: true\n"
                                        "mirror: true\n"
                                        "accept-commands: true\n"
                                        "bodies: [\"ambf/env/*\", \"afhub/arm/*\"]\n"
                                        "devices: falcon*\n"
                                        "world: true\n"
                                        "qos: reliable\n"
                                        "rate: 500\n"
                                        "spin: true\n"
                                        "cpu-wake-latency: 0\n"
                                        "rate-limits: {bodies: 200, devices: 1000, world: 50}\n"
                                        "max-command-age: 0.02\n");
  const DdsBridgeOptions options = read_dds_bridge_config(path);
  EXPECT_EQ(options.domain, 7u);
  EXPECT_EQ(options.interface, "veth0");
  EXPECT_TRUE(options.export_bodies);
  EXPECT_TRUE(options.mirror);
  EXPECT_TRUE(options.accept_commands);
  EXPECT_EQ(options.body_globs, (std::vector<std::string>{"ambf/env/*", "afhub/arm/*"}));
  EXPECT_EQ(options.device_globs, (std::vector<std::string>{"falcon*"}));
  EXPECT_TRUE(options.world);
  EXPECT_TRUE(options.reliable);
  EXPECT_EQ(options.rate_hz, 500.0);
  EXPECT_TRUE(options.spin);
  EXPECT_EQ(options.cpu_wake_latency_us, 0);
  EXPECT_EQ(options.body_rate_hz, 200.0);
  EXPECT_EQ(options.device_rate_hz, 1000.0);
  EXPECT_EQ(options.world_rate_hz, 50.0);
  EXPECT_EQ(options.max_command_age_s, 0.02);
}

TEST(DdsBridgeConfig, KeysNotInTheFileKeepTheirDefaults) {
  afhub::testing::ModelFolder folder;
  DdsBridgeOptions defaults;
  defaults.domain = 4;
  const DdsBridgeOptions options =
      read_dds_bridge_config(folder.write("bridge.yaml", "qos: best-effort\n"), defaults);
  EXPECT_EQ(options.domain, 4u);
  EXPECT_FALSE(options.reliable);
  EXPECT_FALSE(options.spin);
  EXPECT_EQ(options.cpu_wake_latency_us, -1);  // the CPUs left as they are
  EXPECT_EQ(options.body_globs, (std::vector<std::string>{"*"}));
  EXPECT_TRUE(options.device_globs.empty());
}

TEST(DdsBridgeConfig, RefusesUnknownKeysAndBadValuesWithTheirLine) {
  EXPECT_EQ(error_of("export: true\ncolour: red\n").substr(0, 48),
            ":2:1: error: unknown key 'colour'; the keys are ");
  EXPECT_EQ(error_of("domain: 233\n"), ":1:9: error: 'domain' is 233; write a value from 0 to 232");
  EXPECT_EQ(error_of("domain: 1.5\n"),
            ":1:9: error: 'domain' must be a whole number from 0 to 232");
  EXPECT_EQ(error_of("export: yes please\n"), ":1:9: error: 'export' must be true or false");
  EXPECT_EQ(error_of("qos: fast\n"),
            ":1:6: error: 'qos' must be best-effort or reliable (states keep the last 1)");
  EXPECT_EQ(error_of("\nrate-limits: {bodies: 10, joints: 5}\n").substr(0, 37),
            ":2:27: error: unknown topic 'joints' ");
  EXPECT_EQ(error_of("rate-limits: {world: -1}\n"),
            ":1:22: error: 'rate-limits: world' is -1; write a value from 0 to 100000");
  EXPECT_EQ(error_of("max-command-age: 0\n"),
            ":1:18: error: 'max-command-age' is 0; write a value from 1e-09 to 10");
  EXPECT_EQ(error_of("cpu-wake-latency: 2.5\n"),
            ":1:19: error: 'cpu-wake-latency' is whole microseconds");
  EXPECT_EQ(error_of("cpu-wake-latency: 5000\n"),
            ":1:19: error: 'cpu-wake-latency' is 5000; write a value from 0 to 1000");
  EXPECT_EQ(error_of("bodies: {a: 1}\n"),
            ":1:9: error: 'bodies' must be a glob or a list of globs, e.g. [\"ambf/env/*\"]");
  EXPECT_NE(error_of("interface: \"eth0<x>\"\n").find(":1:12: error: interface 'eth0<x>'"),
            std::string::npos);
  EXPECT_EQ(error_of("- a\n- b\n").substr(0, 49),
            ":1:1: error: a bridge config is a map of settings");
  EXPECT_EQ(error_of("export: [true\n").substr(0, 25), ":2:1: error: YAML syntax:");
}

TEST(DdsBridgeConfig, WhatCheckPrintsReadsBackTheSame) {
  DdsBridgeOptions options;
  options.domain = 9;
  options.interface = "eth1";
  options.mirror = true;
  options.body_globs = {"a/*", "b"};
  options.device_globs = {"falcon"};
  options.world = true;
  options.reliable = true;
  options.rate_hz = 250;
  options.body_rate_hz = 0.5;
  options.device_rate_hz = 100;
  options.world_rate_hz = 10;
  options.max_command_age_s = 0.125;
  options.cpu_wake_latency_us = 20;
  afhub::testing::ModelFolder folder;
  const DdsBridgeOptions back =
      read_dds_bridge_config(folder.write("bridge.yaml", render_dds_bridge_config(options)));
  EXPECT_EQ(render_dds_bridge_config(back), render_dds_bridge_config(options));
  EXPECT_EQ(back.domain, 9u);
  EXPECT_EQ(back.interface, "eth1");
  EXPECT_EQ(back.device_globs, options.device_globs);
  EXPECT_EQ(back.body_rate_hz, 0.5);
  EXPECT_EQ(back.max_command_age_s, 0.125);
  EXPECT_EQ(back.cpu_wake_latency_us, 20);
}

TEST(DdsBridgeConfig, TheInterfaceReplacesTheUrisOwn) {
  // Cyclone refuses an interface selected twice, and would add up different ones.
  EXPECT_EQ(
      cyclone_config_with_interface(
          "<CycloneDDS><Domain><General><Interfaces><NetworkInterface name=\"eth0\"/>"
          "</Interfaces><AllowMulticast>false</AllowMulticast></General></Domain></CycloneDDS>",
          "veth1"),
      "<CycloneDDS><Domain><General><AllowMulticast>false</AllowMulticast></General>"
      "</Domain></CycloneDDS>,<General><Interfaces><NetworkInterface name=\"veth1\"/>"
      "</Interfaces></General>");
  EXPECT_EQ(cyclone_config_with_interface("", "lo"),
            "<General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces></General>");
  EXPECT_THROW(interface_config("nosuch-if0"), Error);
}

TEST(DdsBridgeConfig, AMissingFileIsNamed) {
  try {
    read_dds_bridge_config("/nonexistent/bridge.yaml");
    FAIL() << "read a missing file";
  } catch (const Error& error) {
    EXPECT_NE(
        std::string(error.what())
            .find("/nonexistent/bridge.yaml: error: no such file; expected a bridge config file"),
        std::string::npos);
  }
}

}  // namespace
}  // namespace afhub::bridges
