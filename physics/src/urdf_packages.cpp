// URDF mesh URIs to files (see urdf_packages.hpp).
#include "urdf_packages.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "path_kind.hpp"

namespace afhub::physics::urdf_files {
namespace {

namespace fs = std::filesystem;

// The <name> a package.xml gives, or empty: a text search, enough for that one tag.
std::string package_xml_name(const fs::path& folder) {
  std::ifstream in(folder / "package.xml");
  if (!in) return {};
  std::stringstream text;
  text << in.rdbuf();
  const std::string xml = text.str();
  const std::size_t open = xml.find("<name>");
  if (open == std::string::npos) return {};
  const std::size_t begin = open + 6;
  const std::size_t close = xml.find("</name>", begin);
  if (close == std::string::npos) return {};
  std::string name = xml.substr(begin, close - begin);
  const auto first = name.find_first_not_of(" \t\r\n");
  const auto last = name.find_last_not_of(" \t\r\n");
  return first == std::string::npos ? std::string() : name.substr(first, last - first + 1);
}

bool is_package(const fs::path& folder, const std::string& name) {
  std::error_code error;
  if (!fs::is_directory(folder, error)) return false;
  return folder.filename() == name || package_xml_name(folder) == name;
}

// The package folder at or just inside `folder`, or empty.
fs::path find_in(const fs::path& folder, const std::string& name) {
  if (is_package(folder, name)) return folder;
  if (is_package(folder / name, name)) return folder / name;
  return {};
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, separator);)
    if (!part.empty()) parts.push_back(part);
  return parts;
}

std::string checked(const fs::path& path, std::string& looked) {
  if (const std::string why = not_a_regular_file(path); !why.empty()) {
    looked += " " + path.lexically_normal().string() + " (" + why + ")";
    return {};
  }
  return path.lexically_normal().string();
}

}  // namespace

bool leaves_its_package(const std::string& uri) {
  const std::string package_scheme = "package://";
  if (uri.rfind(package_scheme, 0) != 0) return false;
  const std::size_t slash = uri.find('/', package_scheme.size());
  const std::string name = uri.substr(package_scheme.size(), slash - package_scheme.size());
  if (name == "." || name == "..") return true;
  if (slash == std::string::npos) return false;
  const fs::path inside = fs::path(uri.substr(slash + 1)).lexically_normal();
  // An absolute rest ("package://arm//etc/x") replaced the package's folder when joined.
  return inside.is_absolute() || (!inside.empty() && *inside.begin() == "..");
}

std::string resolve_uri(const std::string& uri, const std::string& urdf_dir,
                        const std::vector<std::string>& package_paths, std::string& looked) {
  looked.clear();
  const std::string package_scheme = "package://", file_scheme = "file://";
  if (uri.rfind(file_scheme, 0) == 0) return checked(uri.substr(file_scheme.size()), looked);
  if (uri.rfind(package_scheme, 0) != 0) {
    const fs::path written(uri);
    return checked(written.is_absolute() ? written : fs::path(urdf_dir) / written, looked);
  }
  const std::string rest = uri.substr(package_scheme.size());
  const std::size_t slash = rest.find('/');
  const std::string name = rest.substr(0, slash);
  const std::string inside = slash == std::string::npos ? std::string() : rest.substr(slash + 1);
  std::vector<fs::path> roots(package_paths.begin(), package_paths.end());
  if (const char* ros = std::getenv("ROS_PACKAGE_PATH"))
    for (const std::string& folder : split(ros, ':')) roots.emplace_back(folder);
  std::error_code error;
  const fs::path up_from = fs::absolute(fs::path(urdf_dir.empty() ? "." : urdf_dir), error);
  for (fs::path up = up_from; !up.empty(); up = up.parent_path()) {
    roots.push_back(up);
    if (up == up.parent_path()) break;
  }
  for (const fs::path& root : roots)
    if (const fs::path package = find_in(root, name); !package.empty())
      return checked(package / inside, looked);
  looked =
      " no package '" + name +
      "' (a folder of that name, or whose package.xml names it) in --package-path "
      "folders, ROS_PACKAGE_PATH (" +
      std::string(std::getenv("ROS_PACKAGE_PATH") ? std::getenv("ROS_PACKAGE_PATH") : "unset") +
      "), or " + up_from.string() + " and the folders above it";
  return {};
}

}  // namespace afhub::physics::urdf_files
