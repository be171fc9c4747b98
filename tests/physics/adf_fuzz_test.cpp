// A fuzz test of the ADF loader (issue 13): the example models and, when present,
// the real AMBF models, mutated deterministically (byte flips, truncations,
// numbers replaced by extremes, values by long texts, lines deleted or duplicated,
// YAML punctuation inserted), are loaded, their meshes read and their simulation built (never
// stepped). Each must fail with an afhub::Error that carries a location
// ("file[:line:col]: error: ..."), or load within the loader's bounds and the hub's
// capacities; anything else, or a crash, is a finding.
// AFHUB_FUZZ_CASES sets the number of cases (default 1000), AFHUB_FUZZ_FIRST the first
// (default 0: ctest runs cases 0-499 and 500-999 as two entries), AFHUB_FUZZ_SEED the seed.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>

#include "afhub/physics/adf_loader.hpp"
#include "afhub/physics/mesh.hpp"
#include "afhub/physics/scene_loader.hpp"
#include "afhub/physics/simulation.hpp"
#include "afhub/shm_layout/error.hpp"
#include "model_files.hpp"
#include "shared_models.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

std::uint64_t from_environment(const char* name, std::uint64_t fallback) {
  const char* text = std::getenv(name);
  return text && *text ? std::strtoull(text, nullptr, 10) : fallback;
}

struct Seed {
  std::string name;
  std::string text;
};

// A seed's mesh folders made absolute, so that its mutants, written elsewhere,
// still find their meshes and reach the code past them.
std::string absolute_mesh_folders(const std::string& text, const fs::path& dir) {
  static const std::regex kFolder(R"((^|\n)(\s*(high|low) resolution path:\s*)([^\n]*))");
  std::string out;
  std::sregex_iterator it(text.begin(), text.end(), kFolder), end;
  std::size_t copied = 0;
  for (; it != end; ++it) {
    const std::smatch& m = *it;
    out += text.substr(copied, m.position(4) - copied);
    out += (dir / m.str(4)).lexically_normal().string();
    copied = m.position(4) + m.length(4);
  }
  return out + text.substr(copied);
}

std::vector<Seed> seeds() {
  std::vector<fs::path> folders = {AFHUB_EXAMPLE_MODELS};
  if (testing::shared_models_present()) folders.push_back(testing::kSharedModels);
  std::vector<Seed> out;
  for (const fs::path& folder : folders)
    for (const auto& entry : fs::recursive_directory_iterator(folder))
      if (entry.is_regular_file() && entry.path().extension() == ".yaml") {
        std::ifstream in(entry.path());
        std::stringstream text;
        text << in.rdbuf();
        out.push_back(
            {entry.path().string(), absolute_mesh_folders(text.str(), entry.path().parent_path())});
      }
  std::sort(out.begin(), out.end(), [](const Seed& a, const Seed& b) { return a.name < b.name; });
  return out;
}

// One mutation of `text`, chosen by `random`.
void mutate(std::string& text, std::mt19937_64& random) {
  auto pick = [&](std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(random() % n); };
  static const std::vector<std::string> kExtremes = {"1e308",      "-1e308",
                                                     ".nan",       "nan",
                                                     ".inf",       "-.inf",
                                                     "1e9",        "-1",
                                                     "0",          "-0",
                                                     "4294967296", "18446744073709551616",
                                                     "1e-308",     "99999999999999999999",
                                                     "0x7fffffff", "''"};
  static const std::string kPunctuation = "{}[]:,-&*!|>'\"%@`#?\n\t ";
  switch (random() % 8) {
    case 0:  // a byte flipped
      if (!text.empty()) text[pick(text.size())] ^= static_cast<char>(1u << (random() % 8));
      break;
    case 1:  // cut short
      text.resize(pick(text.size() + 1));
      break;
    case 2: {  // a number replaced by an extreme
      static const std::regex kNumber(R"(-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?)");
      std::vector<std::pair<std::size_t, std::size_t>> numbers;
      for (std::sregex_iterator it(text.begin(), text.end(), kNumber), end; it != end; ++it)
        numbers.emplace_back(it->position(), it->length());
      if (numbers.empty()) break;
      const auto [at, length] = numbers[pick(numbers.size())];
      text.replace(at, length, kExtremes[pick(kExtremes.size())]);
      break;
    }
    case 3:    // a line deleted
    case 4: {  // a line duplicated, next to itself or at the end
      std::vector<std::size_t> starts = {0};
      for (std::size_t i = 0; i < text.size(); ++i)
        if (text[i] == '\n') starts.push_back(i + 1);
      const std::size_t line = pick(starts.size());
      const std::size_t begin = starts[line];
      const std::size_t end = line + 1 < starts.size() ? starts[line + 1] : text.size();
      const std::string copy = text.substr(begin, end - begin);
      if (random() % 7 == 3 || copy.empty())
        text.erase(begin, end - begin);
      else if (random() % 2)
        text.insert(begin, copy);
      else
        text += "\n" + copy;
      break;
    }
    case 5:  // YAML punctuation inserted
      text.insert(pick(text.size() + 1), 1, kPunctuation[pick(kPunctuation.size())]);
      break;
    case 6: {  // a value replaced by a long text (a name past the file system's limit)
      const std::size_t colon = text.find(": ", pick(text.size() + 1));
      if (colon == std::string::npos) break;
      const std::size_t end = std::min(text.find('\n', colon), text.size());
      text.replace(colon + 2, end - colon - 2, std::string(200 + pick(400), 'x'));
      break;
    }
    default:  // a span of the file repeated
      if (!text.empty()) {
        const std::size_t at = pick(text.size());
        text.insert(pick(text.size() + 1), text.substr(at, pick(200)));
      }
      break;
  }
}

// What a model that loads must be (the loader's documented bounds and the hub's
// capacities); "" when it is, else the first thing wrong.
std::string model_problem(const Model& model) {
  std::string problem;
  auto number = [&](double value, double bound, const std::string& what) {
    if (problem.empty() && !(std::abs(value) <= bound))
      problem = what + " is " + std::to_string(value) + ", beyond " + std::to_string(bound);
  };
  auto vec = [&](const Vec3& v, double bound, const std::string& what) {
    number(v.x, bound, what + ".x");
    number(v.y, bound, what + ".y");
    number(v.z, bound, what + ".z");
  };
  std::set<std::string> channels;
  std::vector<std::size_t> rays(model.bodies.size()), actuators(model.bodies.size());
  std::size_t published = 0;
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const BodySpec& body = model.bodies[b];
    number(body.mass_kg, 1e6, body.identifier + " mass");
    number(body.scale, 1e3, body.identifier + " scale");
    vec(body.location.position_m, 1e5, body.identifier + " position");
    vec(body.location.rpy_rad, 1e9, body.identifier + " orientation");
    if (body.inertia_kgm2) vec(*body.inertia_kgm2, 1e9, body.identifier + " inertia");
    for (const Pid& pid : {body.linear_controller, body.angular_controller}) {
      number(pid.p, 1e9, body.identifier + " P");
      number(pid.d, 1e9, body.identifier + " D");
    }
    for (const auto* shapes : {&body.visual_shapes, &body.collision_shapes})
      for (const ShapeSpec& shape : *shapes) {
        vec(shape.box_size_m, 1e8, body.identifier + " box");
        number(shape.radius_m, 1e8, body.identifier + " radius");
        number(shape.height_m, 1e8, body.identifier + " height");
      }
    if (!channels.insert(body.channel).second) problem = "two bodies on " + body.channel;
    if (body.channel == "world") problem = "a body on the world channel";
    if (!body.passive && ++published > 256) problem = "more bodies than the hub holds";
    if (!body.passive && model.descendant_joints[b].size() > 64) problem = "over 64 joints";
  }
  for (const JointSpec& joint : model.joints) {
    vec(joint.parent_pivot_m, 1e5, joint.identifier + " parent pivot");
    vec(joint.child_pivot_m, 1e5, joint.identifier + " child pivot");
    number(joint.stiffness, 1e9, joint.identifier + " stiffness");
    number(joint.damping, 1e9, joint.identifier + " damping");
    number(joint.controller.p, 1e9, joint.identifier + " P");
    number(joint.max_motor_impulse, 1e9, joint.identifier + " max motor impulse");
  }
  for (const SensorSpec& sensor : model.sensors)
    if ((rays[sensor.parent] += sensor.rays.size()) > 32) problem = "over 32 rays on a body";
  for (const ActuatorSpec& actuator : model.actuators)
    if (++actuators[actuator.parent] > 8) problem = "over 8 actuators on a body";
  return problem;
}

// "path: error: ..." or "path:line:col: error: ...", naming a file.
bool located(const std::string& message) {
  static const std::regex kLocated(R"(^[^\n]+?(:[0-9]+:[0-9]+)?: error: [^\n]+[\s\S]*)");
  return std::regex_match(message, kLocated);
}

TEST(AdfFuzz, MutatedModelsLoadOrFailWithALocatedError) {
  const std::uint64_t cases = from_environment("AFHUB_FUZZ_CASES", 1000);
  const std::uint64_t first = from_environment("AFHUB_FUZZ_FIRST", 0);
  const std::uint64_t seed = from_environment("AFHUB_FUZZ_SEED", 1);
  const std::vector<Seed> originals = seeds();
  ASSERT_FALSE(originals.empty());
  testing::ModelFolder folder;
  std::uint64_t loaded = 0, refused = 0, built = 0, findings = 0;
  const auto start = std::chrono::steady_clock::now();
  for (std::uint64_t n = first; n < first + cases; ++n) {
    std::mt19937_64 random(seed * 0x9E3779B97F4A7C15ull + n);
    const Seed& original = originals[random() % originals.size()];
    std::string text = original.text;
    for (int k = 1 + static_cast<int>(random() % 3); k > 0; --k) mutate(text, random);
    const std::string path = folder.write("mutant.yaml", text);
    std::string problem;
    try {
      Model model = load_adf_files({path});
      problem = model_problem(model);
      check_meshes(model);
      // Building costs a Bullet world; every model that loads is built once.
      Simulation sim(model, 0.001);
      if (problem.empty() && !sim.all_finite()) problem = "a built simulation that is not finite";
      ++built;
      ++loaded;
    } catch (const Error& error) {
      ++refused;
      if (!located(error.what()))
        problem = std::string("an error without a location: ") + error.what();
    } catch (const std::exception& error) {
      problem = std::string("not an afhub error: ") + error.what();
    }
    if (problem.empty() && original.name.find("world") != std::string::npos) {
      SceneRequest request;
      request.world_file = path;
      request.adf_files = {AFHUB_EXAMPLE_MODELS "/arm7.yaml"};  // something to simulate
      try {
        load_scene(request);
      } catch (const Error& error) {
        if (!located(error.what()))
          problem = std::string("an error without a location: ") + error.what();
      } catch (const std::exception& error) {
        problem = std::string("not an afhub error: ") + error.what();
      }
    }
    if (!problem.empty()) {
      ++findings;
      ADD_FAILURE() << "case " << n << " (seed " << seed << ", from " << original.name
                    << "): " << problem << "\n--- mutant ---\n"
                    << text.substr(0, 2000);
      if (findings >= 10) break;
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "adf fuzz: %llu cases from %zu seeds (seed %llu) in %.1f s: %llu loaded and built, "
      "%llu refused with a location, %llu findings\n",
      static_cast<unsigned long long>(cases), originals.size(),
      static_cast<unsigned long long>(seed), seconds, static_cast<unsigned long long>(built),
      static_cast<unsigned long long>(refused), static_cast<unsigned long long>(findings));
  (void)loaded;
}

}  // namespace
}  // namespace afhub::physics
