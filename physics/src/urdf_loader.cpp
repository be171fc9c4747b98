// URDF loader (see urdf_loader.hpp). liburdfdom parses the file and builds the tree
// (refusing cycles, links with two parents, unknown links); this file turns each link
// into a BodySpec and each joint into a JointSpec with the paper's Algorithm 3 offset.
// Line numbers come from TinyXML, the XML parser urdfdom itself parses with (its
// header includes it): the file is read into TinyXML first, which locates an XML error
// and every element; urdfdom's own errors, which carry no line, are placed at the
// link or joint they name.
#include "afhub/physics/urdf_loader.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include "afhub/shm_layout/channel_names.hpp"
#include "afhub/shm_layout/error.hpp"
#include "file_reader.hpp"
#include "frames.hpp"
#include "path_kind.hpp"
#include "urdf_packages.hpp"

namespace afhub::physics {
namespace {

namespace fs = std::filesystem;

// A link without <inertial> (or of mass 0) is a frame to URDF tools. Bullet makes a body of
// mass 0 static, which would pin whatever it is joined to; so a frame that moves
// gets this token mass, small beside any real link.
constexpr double kFrameMassKg = 1e-3;
constexpr double kFrameInertiaKgm2 = 1e-7;

// urdfdom's errors and warnings go through console_bridge: collected here while it
// parses, to be said with the file's name instead of on stderr.
class CollectedLog : public console_bridge::OutputHandler {
 public:
  CollectedLog() { console_bridge::useOutputHandler(this); }
  ~CollectedLog() override { console_bridge::restorePreviousOutputHandler(); }
  CollectedLog(const CollectedLog&) = delete;
  CollectedLog& operator=(const CollectedLog&) = delete;
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) messages.push_back(text);
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) errors = true;
  }
  std::vector<std::string> messages;
  // urdfdom drops an element it cannot read (a mass of "nan", a cylinder without its
  // radius), says so as an error and still returns the robot: refused here all the same.
  bool errors = false;
};

// Past this an angle is no angle any file means (and its sine turns to noise: doubles
// are a radian apart at 1e16).
constexpr double kMaxOriginAngleRad = 1e6;

// The file's XML elements, for their lines: the robot, each link and joint by name.
struct XmlElements {
  TiXmlDocument document;
  const TiXmlElement* robot = nullptr;
  std::map<std::string, const TiXmlElement*> links, joints;
};

SourceLocation location_of(const std::string& path, const TiXmlBase& node) {
  return {path, std::max(1, node.Row()), std::max(1, node.Column())};
}

// TinyXML parses an element's children by recursion: 50 000 nested elements
// overflowed the stack of `afhub check`. A URDF nests a few (robot, link, visual,
// geometry, mesh).
constexpr int kMaxXmlDepth = 1000;

// Where `text` first nests elements deeper than kMaxXmlDepth, or nullopt. Reads the
// tags alone (comments, CDATA, declarations and quoted values skipped); what it
// misreads, TinyXML reports next.
std::optional<std::size_t> too_deep_at(const std::string& text) {
  int depth = 0;
  for (std::size_t i = text.find('<'); i != std::string::npos; i = text.find('<', i)) {
    const std::size_t tag = i;
    if (text.compare(i, 4, "<!--") == 0) {
      i = text.find("-->", i);
    } else if (text.compare(i, 9, "<![CDATA[") == 0) {
      i = text.find("]]>", i);
    } else if (text.compare(i, 2, "<?") == 0 || text.compare(i, 2, "<!") == 0) {
      i = text.find('>', i);
    } else if (text.compare(i, 2, "</") == 0) {
      --depth;
      i = text.find('>', i);
    } else {  // a start tag, to its '>' outside quotes
      char quote = 0;
      for (++i; i < text.size() && (quote || text[i] != '>'); ++i)
        if (quote ? text[i] == quote : text[i] == '"' || text[i] == '\'')
          quote = quote ? 0 : text[i];
      if (i < text.size() && text[i - 1] != '/' && ++depth > kMaxXmlDepth) return tag;
    }
    if (i == std::string::npos || i >= text.size()) break;
    ++i;
  }
  return std::nullopt;
}

SourceLocation location_at(const std::string& path, const std::string& text, std::size_t at) {
  const auto line_start = text.rfind('\n', at);
  const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<long>(at), '\n');
  const auto column = at - (line_start == std::string::npos ? 0 : line_start + 1) + 1;
  return {path, static_cast<int>(line), static_cast<int>(column)};
}

// Where a DOCTYPE declares entities or elements ("<!DOCTYPE robot [ ... ]>"), or nullopt.
// TinyXML (and so urdfdom, and ROS) reads no such declarations: it stopped at them and
// the file seemed to have no <robot>.
std::optional<std::size_t> doctype_subset_at(const std::string& text) {
  const std::size_t doctype = text.find("<!DOCTYPE");
  if (doctype == std::string::npos) return std::nullopt;
  const std::size_t bracket = text.find('[', doctype), end = text.find('>', doctype);
  if (bracket < end) return doctype;
  return std::nullopt;
}

// Reads the text as XML: a file that is not well-formed, or has no <robot>, is an
// error at the place TinyXML stopped.
void read_xml(const std::string& path, const std::string& text, XmlElements& xml) {
  if (const std::optional<std::size_t> at = too_deep_at(text))
    fail(location_at(path, text, *at),
         "XML elements nested deeper than " + std::to_string(kMaxXmlDepth) +
             " levels here; a URDF nests a few (robot, link, visual, geometry): is the file "
             "generated as meant?");
  if (const std::optional<std::size_t> at = doctype_subset_at(text))
    fail(location_at(path, text, *at),
         "this DOCTYPE declares entities or elements ([...]), which URDF readers (urdfdom, as "
         "ROS) do not read; write the values in place of the entities and remove the [...]");
  xml.document.SetTabSize(1);  // columns count characters
  xml.document.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (xml.document.Error()) {
    std::string why = xml.document.ErrorDesc();
    if (!why.empty() && why.back() == '.') why.pop_back();
    fail({path, std::max(1, xml.document.ErrorRow()), std::max(1, xml.document.ErrorCol())},
         "not well-formed XML (" + lower(why) +
             "); fix the XML here or just above: a tag left open or closed twice, a missing "
             "quote or '>'");
  }
  xml.robot = xml.document.RootElement();
  if (!xml.robot || xml.robot->ValueStr() != "robot")
    fail(xml.robot ? location_of(path, *xml.robot) : SourceLocation{path, 1, 1},
         "the top element is not <robot name=\"...\">; is this a URDF file?");
  for (const TiXmlElement* e = xml.robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const char* name = e->Attribute("name");
    if (!name) continue;
    if (e->ValueStr() == "link") xml.links.try_emplace(name, e);
    if (e->ValueStr() == "joint") xml.joints.try_emplace(name, e);
  }
}

// The first element under `element` (or itself) with an attribute whose value, or one
// of its space-separated words ("0 0 abc"), is `value`.
const TiXmlElement* holding_value(const TiXmlElement* element, const std::string& value) {
  for (const TiXmlAttribute* a = element->FirstAttribute(); a; a = a->Next()) {
    std::istringstream words(a->ValueStr());
    for (std::string word; words >> word;)
      if (word == value) return element;
  }
  for (const TiXmlElement* e = element->FirstChildElement(); e; e = e->NextSiblingElement())
    if (const TiXmlElement* found = holding_value(e, value)) return found;
  return nullptr;
}

// The element a urdfdom message names, or null: a joint before a link ("child link
// [c] of joint [j]" is the joint's mistake).
const TiXmlElement* named_element(const XmlElements& xml, const std::string& message) {
  static const std::regex named(R"((joint|link)\s*(?:\[([^\]]*)\]|'([^']*)'))", std::regex::icase);
  const TiXmlElement* link = nullptr;
  for (auto it = std::sregex_iterator(message.begin(), message.end(), named);
       it != std::sregex_iterator(); ++it) {
    const bool joint = lower((*it)[1]) == "joint";
    const auto& table = joint ? xml.joints : xml.links;
    auto found = table.find((*it)[2].matched ? (*it)[2].str() : (*it)[3].str());
    if (found == table.end()) continue;
    if (joint) return found->second;
    if (!link) link = found->second;
  }
  return link;
}

// Where urdfdom's first problem is: the joint or link its messages name, down to the
// element holding a value they quote ("mass [1.x] is not a float"); else the <robot>
// element.
SourceLocation urdfdom_error_at(const std::string& path, const XmlElements& xml,
                                const std::vector<std::string>& messages) {
  static const std::regex quoted(R"(\[([^\]]*)\]|\(([^)]*)\) is not)");
  for (std::size_t m = 0; m < messages.size(); ++m) {
    const TiXmlElement* element = named_element(xml, messages[m]);
    if (!element) continue;
    for (std::size_t before = 0; before <= m; ++before)
      for (auto it = std::sregex_iterator(messages[before].begin(), messages[before].end(), quoted);
           it != std::sregex_iterator(); ++it) {
        const std::string value = (*it)[1].matched ? (*it)[1].str() : (*it)[2].str();
        if (value.empty() || value == element->Attribute("name")) continue;
        if (const TiXmlElement* holder = holding_value(element, value))
          return location_of(path, *holder);
      }
    return location_of(path, *element);
  }
  return location_of(path, *xml.robot);
}

std::string read_text(const std::string& path) {
  if (const std::string why = not_a_regular_file(path); !why.empty())
    throw Error(path + ":1:1: error: the URDF file " + why);
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  if (!in) throw Error(path + ":1:1: error: the URDF file cannot be read");
  return text.str();
}

btTransform to_bt(const urdf::Pose& pose) {
  return btTransform(
      btQuaternion(pose.rotation.x, pose.rotation.y, pose.rotation.z, pose.rotation.w),
      btVector3(pose.position.x, pose.position.y, pose.position.z));
}

Placement placement(const btTransform& transform) {
  return {from_bt(transform.getOrigin()), rpy_of(transform.getBasis())};
}

bool is_identity(const urdf::Pose& pose) {
  const btTransform t = to_bt(pose);
  return t.getOrigin().length() < 1e-12 && std::abs(std::abs(t.getRotation().w()) - 1.0) < 1e-12;
}

class UrdfReader {
 public:
  UrdfReader(const std::string& path, const UrdfOptions& options, Model& model)
      : path_(path),
        dir_(fs::path(path).parent_path().string()),
        options_(options),
        model_(model) {}
  // urdfdom's links hold their children by shared_ptr: a link its own child (refused in
  // place_links) would keep itself, and the links below, alive for good.
  ~UrdfReader() {
    if (robot_)
      for (const auto& [name, link] : robot_->links_) link->child_links.clear();
  }
  UrdfReader(const UrdfReader&) = delete;
  UrdfReader& operator=(const UrdfReader&) = delete;

  void load() {
    const std::string text = read_text(path_);
    if (fs::path(path_).extension() == ".xacro" || text.find("<xacro:") != std::string::npos)
      fail({path_, 1, 1},
           "this is a xacro file (it uses <xacro:...> macros); expand it to a URDF first, "
           "e.g. `xacro robot.urdf.xacro > robot.urdf` on a ROS machine (xacro is not in "
           "Debian 12)");
    read_xml(path_, text, xml_);
    {
      CollectedLog log;
      robot_ = urdf::parseURDF(text);
      if (!robot_ || log.errors) {
        std::string why = log.messages.empty() ? "urdfdom refused it" : log.messages.front();
        for (std::size_t i = 1; i < log.messages.size(); ++i) why += "; " + log.messages[i];
        while (!why.empty() && why.back() == '.') why.pop_back();
        fail(urdfdom_error_at(path_, xml_, log.messages),
             "not a valid URDF: " + why +
                 ". Fix it here (the format: https://wiki.ros.org/urdf/XML)");
      }
    }
    check_origin_angles(*xml_.robot);
    warn_unread_elements();
    name_space_ = "/ambf/env/" + robot_->getName() + "/";
    model_.notes.push_back(path_ + ": robot '" + robot_->getName() +
                           "': links joined by a joint do not collide with each other (URDF's "
                           "convention), nor links that overlap as built (MoveIt's rule)");
    place_links();
    read_links();
    read_joints();
    model_.file_ignores_inter_collision.push_back(false);
    model_.file_parts_overlaps.push_back(true);
  }

 private:
  SourceLocation link_at(const std::string& name) const {
    auto found = xml_.links.find(name);
    return location_of(path_, found == xml_.links.end() ? *xml_.robot : *found->second);
  }
  SourceLocation joint_at(const std::string& name) const {
    auto found = xml_.joints.find(name);
    return location_of(path_, found == xml_.joints.end() ? *xml_.robot : *found->second);
  }
  void warn(int line, const std::string& what) {
    model_.warnings.push_back(path_ + ":" + std::to_string(line) + ":1: warning: " + what);
  }
  void warn_once(const std::string& key, int line, const std::string& what) {
    if (warned_.insert(key).second) warn(line, what);
  }

  // Each kind of element afhub does not read, once, at its first: <transmission> and
  // <gazebo> as ROS tools' own, and any other (a <sensor>, a misspelt <colision>),
  // which went by without a word.
  void warn_unread_elements() {
    const auto look = [&](const TiXmlElement& parent, const std::set<std::string>& known,
                          const std::string& in, const std::string& reads) {
      for (const TiXmlElement* child = parent.FirstChildElement(); child;
           child = child->NextSiblingElement()) {
        const std::string name = child->ValueStr();
        if (known.count(name)) continue;
        const bool tool = in.empty() && (name == "transmission" || name == "gazebo");
        warn_once(in + "<" + name + ">", location_of(path_, *child).line,
                  "<" + name + "> elements" + (in.empty() ? "" : " in a " + in) +
                      (tool ? " are ignored (afhub simulates the links and joints)"
                            : " are not read (afhub reads " + reads + ")"));
      }
    };
    look(*xml_.robot, {"link", "joint", "material"}, "", "<link>, <joint> and <material>");
    for (const TiXmlElement* child = xml_.robot->FirstChildElement(); child;  // in file order
         child = child->NextSiblingElement()) {
      if (child->ValueStr() == "link")
        look(*child, {"inertial", "visual", "collision"}, "link",
             "<inertial>, <visual> and <collision>");
      if (child->ValueStr() == "joint")
        look(*child,
             {"origin", "parent", "child", "axis", "limit", "dynamics", "mimic", "calibration",
              "safety_controller"},
             "joint", "its <origin>, <parent>, <child>, <axis>, <limit>, <dynamics> and <mimic>");
    }
  }

  // Every <origin rpy> below `element`: urdfdom turns it into a rotation at once, and
  // took 1e300 (whose sine is noise) as some rotation, and 90 (degrees?) as 90 rad.
  void check_origin_angles(const TiXmlElement& element) {
    for (const TiXmlElement* child = element.FirstChildElement(); child;
         child = child->NextSiblingElement()) {
      check_origin_angles(*child);
      const char* rpy = child->Value() == std::string("origin") ? child->Attribute("rpy") : nullptr;
      if (!rpy) continue;
      std::istringstream values(rpy);
      for (double angle = 0.0; values >> angle;) {
        if (!(std::abs(angle) <= kMaxOriginAngleRad))
          fail(location_of(path_, *child),
               "<origin rpy=\"" + std::string(rpy) + "\"> holds " + yaml::number_text(angle) +
                   ", which is no angle a rotation can be computed from; give radians within " +
                   yaml::number_text(kMaxOriginAngleRad));
        if (std::abs(angle) > 2.0 * M_PI * 1.01)
          warn_once("rpy", child->Row(),
                    "<origin rpy=\"" + std::string(rpy) +
                        "\"> turns more than a full turn: URDF gives it in radians (90 degrees "
                        "is 1.5708); check its unit");
      }
    }
  }

  // A value within the bounds an ADF file has for it (file_reader.hpp), or an error at
  // `at` naming `what`: past them Bullet's arithmetic overflows while stepping.
  static void require_within(double value, double low, double high, const SourceLocation& at,
                             const std::string& what) {
    if (value >= low && value <= high) return;
    fail(at, what + " is " + yaml::number_text(value) + "; give a number from " +
                 yaml::number_text(low) + " to " + yaml::number_text(high));
  }
  // A shape's size: above 0, at most kMaxLengthM.
  static void require_size(double value, const SourceLocation& at, const std::string& what) {
    if (value > 0.0 && value <= kMaxLengthM) return;
    fail(at, what + " is " + yaml::number_text(value) + "; give a size above 0 and at most " +
                 yaml::number_text(kMaxLengthM) + " m");
  }

  // Each link's world pose at the zero configuration, from the root down. urdfdom
  // takes a link that is the child of two joints (of itself, even) as long as one root
  // is left: refused here, where the walk would place it twice, or forever.
  void place_links() {
    // Before the walk: a link its own child is not below the root at all (urdfdom takes
    // another link for the root), and the walk would never reach it.
    for (const auto& [name, joint] : robot_->joints_)
      if (joint->parent_link_name == joint->child_link_name)
        fail(joint_at(name), "joint '" + name + "' has link '" + joint->child_link_name +
                                 "' as both its parent and its child; a joint joins two "
                                 "different links");
    std::vector<urdf::LinkConstSharedPtr> stack{robot_->getRoot()};
    world_[robot_->getRoot()->name] = btTransform::getIdentity();
    std::map<std::string, std::string> parent_joint;  // of each link placed
    while (!stack.empty()) {
      const urdf::LinkConstSharedPtr link = stack.back();
      stack.pop_back();
      for (const auto& joint : link->child_joints) {
        const std::string& child = joint->child_link_name;
        const auto [first, placed] = parent_joint.emplace(child, joint->name);
        if (!placed)
          fail(joint_at(joint->name),
               "joint '" + joint->name + "' makes link '" + child +
                   "' a child a second time: it is the child of joint '" + first->second +
                   "'. A URDF's links form a tree, each the child of one joint: remove one "
                   "of the two (for a closed loop, convert the robot with `afhub convert` and "
                   "close it with an ADF joint)");
        world_[child] = world_[link->name] * to_bt(joint->parent_to_joint_origin_transform);
        stack.push_back(robot_->getLink(joint->child_link_name));
      }
    }
    for (const auto& [name, link] : robot_->links_)
      if (!world_.contains(name))
        fail(link_at(name), "link '" + name + "' is not below the root link '" +
                                robot_->getRoot()->name +
                                "': its joints close a cycle. A URDF's links form one tree "
                                "from the root, each the child of one joint");
  }

  std::string mesh_path(const urdf::Mesh& mesh, const std::string& link, const char* role) {
    if (urdf_files::leaves_its_package(mesh.filename))
      fail(link_at(link), "link '" + link + "': " + role + " mesh '" + mesh.filename +
                              "' leads out of its package; a package:// path names a file "
                              "inside the package (package://NAME/meshes/part.stl)");
    std::string looked;
    std::string resolved =
        urdf_files::resolve_uri(mesh.filename, dir_, options_.package_paths, looked);
    if (resolved.empty())
      fail(link_at(link), "link '" + link + "': " + role + " mesh '" + mesh.filename +
                              "' was not found; looked in:" + looked +
                              ". Give its package's folder with --package-path DIR");
    // Absolute: a file converted to ADF (`afhub convert -o elsewhere/`) finds it too.
    return fs::absolute(resolved).lexically_normal().string();
  }

  // A mesh's scale per axis, each within the bound ADF scales have, and negative for a
  // mirrored mesh (as RViz and Gazebo take it), never 0.
  Vec3 mesh_scale(const urdf::Mesh& mesh, const std::string& link) {
    const urdf::Vector3& s = mesh.scale;
    for (double axis : {s.x, s.y, s.z})
      if (!(std::abs(axis) > 0) || std::abs(axis) > kMaxScale)
        fail(link_at(link), "link '" + link + "': mesh '" + mesh.filename + "' has scale " +
                                yaml::number_text(s.x) + " " + yaml::number_text(s.y) + " " +
                                yaml::number_text(s.z) +
                                "; give each axis a scale other than 0 within -1000 to 1000 "
                                "(a negative one mirrors the mesh)");
    return {s.x, s.y, s.z};
  }

  // A box, cylinder or sphere of `link` at `origin` in its frame; false for a mesh.
  bool primitive(const urdf::Geometry& geometry, const urdf::Pose& origin, const std::string& link,
                 ShapeSpec& shape) const {
    shape.offset = placement(to_bt(origin));
    const SourceLocation at = link_at(link);
    const std::string what = "link '" + link + "': <";
    switch (geometry.type) {
      case urdf::Geometry::BOX: {
        const auto& box = static_cast<const urdf::Box&>(geometry);
        for (const double side : {box.dim.x, box.dim.y, box.dim.z})
          require_size(side, at, what + "box size> side");
        shape.kind = ShapeKind::kBox;
        shape.box_size_m = {box.dim.x, box.dim.y, box.dim.z};
        return true;
      }
      case urdf::Geometry::CYLINDER: {
        const auto& cylinder = static_cast<const urdf::Cylinder&>(geometry);
        require_size(cylinder.radius, at, what + "cylinder radius>");
        require_size(cylinder.length, at, what + "cylinder length>");
        shape.kind = ShapeKind::kCylinder;
        shape.radius_m = cylinder.radius;
        shape.height_m = cylinder.length;
        shape.axis = 2;  // URDF cylinders lie along z
        return true;
      }
      case urdf::Geometry::SPHERE:
        require_size(static_cast<const urdf::Sphere&>(geometry).radius, at,
                     what + "sphere radius>");
        shape.kind = ShapeKind::kSphere;
        shape.radius_m = static_cast<const urdf::Sphere&>(geometry).radius;
        return true;
      default:
        return false;
    }
  }

  void read_geometry(const urdf::Link& link, BodySpec& body) {
    struct LinkMesh {
      PlacedMesh placed;
      bool at_origin;  // no <origin>, or an identity one
    };
    auto link_mesh = [&](const urdf::Geometry& geometry, const urdf::Pose& origin,
                         const char* kind) {
      const auto& mesh = static_cast<const urdf::Mesh&>(geometry);
      return LinkMesh{
          {mesh_path(mesh, link.name, kind), placement(to_bt(origin)), mesh_scale(mesh, link.name)},
          is_identity(origin)};
    };
    std::vector<LinkMesh> visuals, collisions;
    for (const auto& visual : link.visual_array) {
      if (!visual->geometry) continue;
      if (visual->material && !body.color_rgba) {
        const urdf::Color& c = visual->material->color;
        body.color_rgba = std::array<double, 4>{c.r, c.g, c.b, c.a};
      }
      ShapeSpec shape;
      if (primitive(*visual->geometry, visual->origin, link.name, shape))
        body.visual_shapes.push_back(shape);
      else
        visuals.push_back(link_mesh(*visual->geometry, visual->origin, "visual"));
    }
    for (const auto& collision : link.collision_array) {
      if (!collision->geometry) continue;
      ShapeSpec shape;
      if (primitive(*collision->geometry, collision->origin, link.name, shape))
        body.collision_shapes.push_back(shape);
      else
        collisions.push_back(link_mesh(*collision->geometry, collision->origin, "collision"));
    }
    // The body's scale is its first mesh's, when the same on every axis. A mesh at the
    // link frame at that scale is the body's own mesh, as an ADF body's; the others
    // are placed, each at its origin and scale.
    const LinkMesh* first = !visuals.empty()      ? &visuals.front()
                            : !collisions.empty() ? &collisions.front()
                                                  : nullptr;
    const Vec3* s = first ? &first->placed.scale : nullptr;
    body.scale = s && s->x > 0 && s->x == s->y && s->x == s->z ? s->x : 1.0;
    auto own = [&](const LinkMesh& mesh) {
      const Vec3& m = mesh.placed.scale;
      return mesh.at_origin && m.x == body.scale && m.y == body.scale && m.z == body.scale;
    };
    for (const LinkMesh& mesh : visuals) {
      if (body.visual_mesh.empty() && body.visual_mesh_parts.empty() && own(mesh))
        body.visual_mesh = mesh.placed.path;
      else
        body.visual_mesh_parts.push_back(mesh.placed);
    }
    // One such mesh collides as that mesh; anything more as one compound.
    if (collisions.size() == 1 && own(collisions.front()) && body.collision_shapes.empty())
      body.collision_mesh = collisions.front().placed.path;
    else
      for (const LinkMesh& mesh : collisions) body.collision_mesh_parts.push_back(mesh.placed);
    // Convex hulls for moving meshes, as ADF bodies; a static one keeps its triangles.
    body.collision_mesh_type = CollisionMeshType::kTrimesh;
  }

  // Mass and the full inertia tensor at the inertial origin, diagonalised: the
  // inertial offset's rotation turns onto the principal axes.
  void read_inertial(const urdf::Link& link, BodySpec& body) {
    if (!link.inertial) {
      body.mass_kg = 0.0;
      return;
    }
    const urdf::Inertial& in = *link.inertial;
    const std::string what = "link '" + link.name + "': <";
    require_within(in.mass, 0.0, kMaxMassKg, link_at(link.name), what + "mass> (kg)");
    if (in.mass > 0.0 && in.mass < kMinMovingMassKg)
      fail(link_at(link.name), what + "mass> is " + yaml::number_text(in.mass) + " kg, below the " +
                                   yaml::number_text(kMinMovingMassKg) +
                                   " kg a moving link needs (Bullet divides by it)");
    for (const auto& [name, value] : {std::pair{"ixx", in.ixx},
                                      {"ixy", in.ixy},
                                      {"ixz", in.ixz},
                                      {"iyy", in.iyy},
                                      {"iyz", in.iyz},
                                      {"izz", in.izz}})
      require_within(value, -yaml::kMaxMagnitude, yaml::kMaxMagnitude, link_at(link.name),
                     what + "inertia> " + name);
    body.mass_kg = in.mass;
    Eigen::Matrix3d tensor;
    tensor << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(tensor);
    Eigen::Matrix3d axes = solver.eigenvectors();
    if (axes.determinant() < 0) axes.col(2) = -axes.col(2);
    const Eigen::Vector3d moments = solver.eigenvalues();
    const double largest = std::max(std::abs(moments.maxCoeff()), 1e-300);
    if (moments.minCoeff() < -1e-9 * largest || !std::isfinite(moments.sum()))
      fail(link_at(link.name), "link '" + link.name +
                                   "': its <inertia> is not a physical inertia tensor (negative "
                                   "principal moments); check ixx..izz and their signs");
    const btMatrix3x3 principal(axes(0, 0), axes(0, 1), axes(0, 2), axes(1, 0), axes(1, 1),
                                axes(1, 2), axes(2, 0), axes(2, 1), axes(2, 2));
    const btTransform origin = to_bt(in.origin);
    body.inertial_offset =
        placement(btTransform(origin.getBasis() * principal, origin.getOrigin()));
    body.inertia_kgm2 =
        Vec3{std::max(moments[0], 0.0), std::max(moments[1], 0.0), std::max(moments[2], 0.0)};
    if (!possible_principal_inertias(*body.inertia_kgm2)) {
      char computed[96];  // six digits: a computation's last digits are noise
      std::snprintf(computed, sizeof computed, "%g, %g, %g", moments[0], moments[1], moments[2]);
      warn(link_at(link.name).line,
           "link '" + link.name + "': its <inertia> has principal moments (" + computed +
               ") of which one is larger than the other two together, which no rigid body has; "
               "check ixx..izz");
    }
    if (in.mass > 0.0 && moments.minCoeff() <= 1e-12 * largest)
      warn(link_at(link.name).line,
           "link '" + link.name +
               "': its <inertia> has a zero principal moment: Bullet takes it as infinite, so "
               "the link cannot turn about that axis; give ixx..izz");
  }

  void read_links() {
    const std::string root = robot_->getRoot()->name;
    std::vector<urdf::LinkSharedPtr> links;
    robot_->getLinks(links);
    // File order is lost in urdfdom's map: the tag lines give it back.
    std::sort(links.begin(), links.end(), [&](const auto& a, const auto& b) {
      return link_at(a->name).line < link_at(b->name).line;
    });
    for (const auto& link : links) {
      BodySpec body;
      body.identifier = "BODY " + link->name;
      body.name = link->name;
      std::erase(body.name, ' ');
      body.channel = body_channel_name(name_space_, body.name);
      body.qualified_identifier = name_space_ + body.identifier;
      body.where = link_at(link->name);
      body.file_index = static_cast<int>(model_.file_ignores_inter_collision.size());
      if (auto problem = channel_name_problem(body.channel); !problem.empty())
        fail(body.where, problem);
      body.location = placement(world_.at(link->name));
      read_inertial(*link, body);
      read_geometry(*link, body);
      if (link->name == root) {
        place_root(*link, body);
      } else if (body.mass_kg == 0.0) {
        body.mass_kg = kFrameMassKg;
        body.inertia_kgm2 = Vec3{kFrameInertiaKgm2, kFrameInertiaKgm2, kFrameInertiaKgm2};
        frames_.push_back(link->name);
      }
      body_index_[link->name] = static_cast<int>(model_.bodies.size());
      model_.bodies.push_back(std::move(body));
    }
    if (!frames_.empty()) {
      std::string names;
      for (const auto& name : frames_) names += (names.empty() ? "" : ", ") + name;
      model_.notes.push_back(path_ + ": links without mass are frames, simulated with " +
                             "a token mass of 1 g so they follow their joints: " + names);
    }
  }

  void place_root(const urdf::Link& link, BodySpec& body) {
    const std::string note = path_ + ": root link '" + link.name + "' ";
    if (link.name == "world") {
      body.mass_kg = 0.0;
      model_.notes.push_back(note + "is fixed to the world (URDF's convention for `world`)");
    } else if (options_.floating_base) {
      if (!link.inertial) {
        body.mass_kg = kFrameMassKg;
        body.inertia_kgm2 = Vec3{kFrameInertiaKgm2, kFrameInertiaKgm2, kFrameInertiaKgm2};
      }
      model_.notes.push_back(note + "floats free (--floating-base)");
    } else {
      body.mass_kg = 0.0;
      model_.notes.push_back(note +
                             "is fixed to the world, as by default (--floating-base frees it)");
    }
  }

  // Algorithm 3: the parent axis is the URDF axis turned by the joint origin, the
  // child axis the URDF axis itself (the child frame is the joint frame), and the
  // offset is the turn about the parent axis left after taking the child axis onto
  // the parent axis the short way: with it the joint reads zero at the URDF's zero.
  static void place_joint(const urdf::Joint& urdf_joint, JointSpec& joint) {
    const btTransform origin = to_bt(urdf_joint.parent_to_joint_origin_transform);
    btVector3 axis(urdf_joint.axis.x, urdf_joint.axis.y, urdf_joint.axis.z);
    if (urdf_joint.type == urdf::Joint::FIXED || urdf_joint.type == urdf::Joint::FLOATING ||
        axis.length() < 1e-12)
      axis = btVector3(0, 0, 1);
    axis.normalize();
    const btVector3 parent_axis = origin.getBasis() * axis;
    joint.parent_pivot_m = from_bt(origin.getOrigin());
    joint.parent_axis = from_bt(parent_axis);
    joint.child_pivot_m = {};
    joint.child_axis = from_bt(axis);
    joint.offset_rad = joint_offset_about(origin.getRotation(), axis, parent_axis);
  }

  void read_joints() {
    std::vector<std::pair<int, urdf::JointSharedPtr>> joints;
    for (const auto& [name, joint] : robot_->joints_)
      joints.emplace_back(joint_at(name).line, joint);
    std::sort(joints.begin(), joints.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    std::map<std::string, int> joint_index;
    const std::size_t first = model_.joints.size();
    for (const auto& [line, urdf_joint] : joints) {
      JointSpec joint;
      joint.identifier = "JOINT " + urdf_joint->name;
      joint.name = urdf_joint->name;
      joint.channel = body_channel_name(name_space_, joint.name);
      joint.where = joint_at(urdf_joint->name);
      joint.parent = body_index_.at(urdf_joint->parent_link_name);
      joint.child = body_index_.at(urdf_joint->child_link_name);
      read_type(*urdf_joint, joint);
      const urdf::Vector3& axis = urdf_joint->axis;
      if ((has_joint_axis(joint.type) || urdf_joint->type == urdf::Joint::PLANAR) &&
          !(std::sqrt(axis.x * axis.x + axis.y * axis.y + axis.z * axis.z) > 1e-12))
        fail(joint.where, "joint '" + joint.name +
                              "': its <axis> is zero; give the direction it turns or slides "
                              "about, e.g. <axis xyz=\"0 0 1\"/>");
      const urdf::Vector3& at = urdf_joint->parent_to_joint_origin_transform.position;
      for (const double coordinate : {at.x, at.y, at.z})
        require_within(coordinate, -kMaxLengthM, kMaxLengthM, joint.where,
                       "joint '" + joint.name + "': <origin xyz> (m)");
      place_joint(*urdf_joint, joint);
      if (urdf_joint->dynamics) {
        require_within(urdf_joint->dynamics->damping, -yaml::kMaxMagnitude, yaml::kMaxMagnitude,
                       joint.where, "joint '" + joint.name + "': <dynamics damping>");
        joint.damping = std::max(0.0, urdf_joint->dynamics->damping);
        if (urdf_joint->dynamics->friction != 0.0)
          warn_once("friction", line,
                    "<dynamics friction> is ignored (afhub applies joint damping only)");
      }
      if (urdf_joint->safety) warn_once("safety", line, "<safety_controller> elements are ignored");
      if (urdf_joint->calibration)
        warn_once("calibration", line, "<calibration> elements are ignored");
      joint_index[joint.name] = static_cast<int>(model_.joints.size());
      model_.joints.push_back(std::move(joint));
    }
    for (const auto& [line, urdf_joint] : joints) {
      if (!urdf_joint->mimic) continue;
      JointSpec& joint = model_.joints[joint_index.at(urdf_joint->name)];
      auto leader = joint_index.find(urdf_joint->mimic->joint_name);
      if (leader == joint_index.end())
        fail(joint.where, "joint '" + joint.name + "' mimics joint '" +
                              urdf_joint->mimic->joint_name +
                              "', which this URDF does not have; fix <mimic joint=...>");
      if (!has_joint_axis(joint.type) || !has_joint_axis(model_.joints[leader->second].type))
        fail(joint.where, "joint '" + joint.name +
                              "': <mimic> needs a revolute, continuous or prismatic joint "
                              "following another");
      require_within(urdf_joint->mimic->multiplier, -yaml::kMaxMagnitude, yaml::kMaxMagnitude,
                     joint.where, "joint '" + joint.name + "': <mimic multiplier>");
      require_within(urdf_joint->mimic->offset, -yaml::kMaxMagnitude, yaml::kMaxMagnitude,
                     joint.where, "joint '" + joint.name + "': <mimic offset>");
      joint.mimic = Mimic{leader->second, urdf_joint->mimic->multiplier, urdf_joint->mimic->offset};
    }
    // A chain of mimics that comes back to itself would never settle.
    for (std::size_t j = first; j < model_.joints.size(); ++j) {
      std::size_t steps = 0;
      for (const JointSpec* at = &model_.joints[j]; at->mimic;
           at = &model_.joints[at->mimic->joint])
        if (++steps > model_.joints.size())
          fail(model_.joints[j].where,
               "joint '" + model_.joints[j].name + "' is in a cycle of <mimic> joints");
    }
  }

  void read_type(const urdf::Joint& urdf_joint, JointSpec& joint) {
    const auto& limits = urdf_joint.limits;
    switch (urdf_joint.type) {
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::PRISMATIC:
        joint.type =
            urdf_joint.type == urdf::Joint::REVOLUTE ? JointType::kRevolute : JointType::kPrismatic;
        if (limits) {
          if (limits->lower > limits->upper)
            fail(joint.where, "joint '" + joint.name + "': <limit> lower " +
                                  yaml::number_text(limits->lower) + " is above upper " +
                                  yaml::number_text(limits->upper) + "; swap them");
          joint.limit_low = limits->lower;
          joint.limit_high = limits->upper;
        }
        break;
      case urdf::Joint::CONTINUOUS:
        joint.type = JointType::kContinuous;
        break;
      case urdf::Joint::FIXED:
        joint.type = JointType::kFixed;
        break;
      case urdf::Joint::FLOATING:
        joint.type = JointType::kSixDof;  // no limits: every direction free
        break;
      case urdf::Joint::PLANAR: {
        // Free along x and y of the joint frame (whose z is the URDF axis), and about
        // z; lower above upper means free to Bullet.
        joint.type = JointType::kSixDof;
        SixDofLimits plane;
        plane.linear_low = {1, 1, 0};
        plane.linear_high = {-1, -1, 0};
        plane.angular_low = {0, 0, 1};
        plane.angular_high = {0, 0, -1};
        joint.multi_limits = plane;
        break;
      }
      default:
        fail(joint.where, "joint '" + joint.name + "' has an unknown type");
    }
    if (limits) {
      const std::string what = "joint '" + joint.name + "': <limit ";
      require_within(limits->effort, 0.0, yaml::kMaxMagnitude, joint.where, what + "effort>");
      require_within(limits->velocity, 0.0, yaml::kMaxMagnitude, joint.where, what + "velocity>");
      for (const auto& [name, value] :
           {std::pair{"lower>", limits->lower}, {"upper>", limits->upper}})
        require_within(value, -yaml::kMaxMagnitude, yaml::kMaxMagnitude, joint.where, what + name);
      // Past a turn each way a revolute limit is no limit: likely degrees (as in ADF).
      if (urdf_joint.type == urdf::Joint::REVOLUTE &&
          std::max(std::abs(limits->lower), std::abs(limits->upper)) > 2.0 * M_PI * 1.01)
        warn(joint.where.line, "joint '" + joint.name + "': <limit lower=\"" +
                                   yaml::number_text(limits->lower) + "\" upper=\"" +
                                   yaml::number_text(limits->upper) +
                                   "\"> reaches past a full turn: URDF gives it in radians (90 "
                                   "degrees is 1.5708); check its unit");
    }
    // URDF's effort limit, as the motor's impulse per step at the default 1 kHz step.
    if (limits && limits->effort > 0 && has_joint_axis(joint.type))
      joint.max_motor_impulse = limits->effort * 1e-3;
    // 0 is what many files give for none.
    if (limits && limits->velocity > 0 && has_joint_axis(joint.type))
      joint.max_velocity = limits->velocity;
  }

  const std::string path_, dir_;
  const UrdfOptions& options_;
  Model& model_;
  XmlElements xml_;
  urdf::ModelInterfaceSharedPtr robot_;
  std::string name_space_;
  std::map<std::string, btTransform> world_;
  std::map<std::string, int> body_index_;
  std::vector<std::string> frames_;
  std::set<std::string> warned_;
};

}  // namespace

bool is_urdf_path(const std::string& path) {
  const std::string extension = fs::path(path).extension().string();
  return extension == ".urdf" || extension == ".URDF" || extension == ".xacro";
}

void load_urdf_into(const std::string& path, const UrdfOptions& options, Model& model) {
  UrdfReader(path, options, model).load();
}

}  // namespace afhub::physics
