// URDF import (urdf.hpp). Three passes over one text, after a scan of its depth (DepthScan):
//   1. TinyXML (the library liburdfdom itself parses with): well-formedness, then the structure with
//      line numbers (names, joint types, parent and child links, one root, every link reached) and the
//      Gazebo spring tags liburdfdom skips;
//   2. liburdfdom's parseURDF: the values (origins, axes, limits, dynamics, inertials), its console
//      output captured; when it rejects the file, each element alone finds the one it rejects;
//   3. the TreeSpec, parents first, every check at the line of the element it concerns.
#include "description/urdf.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <strings.h>  // strncasecmp

#include "common/closest.hpp"
#include "common/errors.hpp"
#include "multibody/limits.hpp"

namespace ff {

namespace {

std::string quoted(const char* kind, const std::string& name) { return std::string(kind) + " \"" + name + "\""; }

std::string fmt(double x) {
  std::ostringstream o;
  o << x;
  return o.str();
}

// The element's line (0 when unknown).
int row(const TiXmlElement* e) { return e ? e->Row() : 0; }

[[noreturn]] void fail(const std::string& source, const TiXmlElement* at, const std::string& what,
                       const std::string& message) {
  throw ConfigError(source, row(at), what, message);
}

// ---- pass 0: before TinyXML ---------------------------------------------------------------------

// TinyXML parses nested elements by recursion, a few stack frames per level: a hostile file nests deep
// enough to overflow the stack. This scan walks the text as TinyXML 2.6 tokenises it (comments, CDATA,
// declarations and unknown <!...> skipped, attribute values quoted after '=', numeric character
// references, which TinyXML reads up to the next ';') and refuses the file at the first element deeper
// than kMaxUrdfDepth, or at the first byte that is not UTF-8 (TinyXML reads a UTF-8 lead byte and the
// bytes after it as one character: the tags it sees would differ from the ones counted here). It stops
// only where TinyXML stops with an error, or at a NUL; fuzz/urdf_fuzz.cpp holds it to that.
class DepthScan {
 public:
  DepthScan(const std::string& xml, const std::string& source) : s_(xml.c_str()), source_(source) {}

  void run() {
    check_utf8();
    int depth = 0;
    while (*p_) {
      if (*p_ != '<') {
        if (!text_until('<')) return;
      } else if (starts("</")) {
        depth = std::max(depth - 1, 0);
        skip_past(">");
      } else if (starts("<!--")) {
        skip_past("-->");
      } else if (starts("<![CDATA[")) {
        skip_past("]]>");
      } else if (starts_nocase("<?xml")) {
        p_ += 5;
        if (!declaration()) return;
      } else if (name_start(p_[1])) {
        const char* tag = p_;
        ++p_;
        const int kind = start_tag();
        if (kind < 0) return;
        if (kind == 1 && ++depth > kMaxUrdfDepth)
          throw ConfigError(source_, line_at(tag), "<" + name_at(tag + 1) + ">",
                            "elements nested more than " + std::to_string(kMaxUrdfDepth) +
                                " deep (a URDF nests about 5): refused before parsing");
      } else {
        skip_past(">");  // TinyXML's "unknown": <!DOCTYPE ...>, <?...>, < followed by no name
      }
    }
  }

 private:
  static bool space(char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; }
  // TinyXML's IsAlpha and IsAlphaNum: any byte from 127 on counts as a letter.
  static bool name_start(char c) { return static_cast<unsigned char>(c) >= 127 || std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
  static bool name_char(char c) { return name_start(c) || std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '.' || c == ':'; }

  bool starts(const char* text) const { return std::strncmp(p_, text, std::strlen(text)) == 0; }
  bool starts_nocase(const char* text) const { return strncasecmp(p_, text, std::strlen(text)) == 0; }
  // TinyXML's SkipWhiteSpace, which in UTF-8 also skips the byte-order mark and U+FFFE, U+FFFF.
  void skip_space() {
    for (;;) {
      if (starts("\xEF\xBB\xBF") || starts("\xEF\xBF\xBE") || starts("\xEF\xBF\xBF")) p_ += 3;
      else if (space(*p_)) ++p_;
      else return;
    }
  }
  // TinyXML's ReadText: up to `end` (or the NUL), a character reference "&#...;" read as one character;
  // false where TinyXML finds a bad reference.
  bool text_until(char end) {
    while (*p_ && *p_ != end) {
      if (p_[0] == '&' && p_[1] == '#' && p_[2]) {
        // TinyXML takes the next ';' and checks the digits back from it to the last 'x' (or '#').
        const bool hex = p_[2] == 'x';
        const char* semi = hex && !p_[3] ? nullptr : std::strchr(p_ + (hex ? 3 : 2), ';');
        if (!semi) return false;
        const char* q = semi - 1;
        for (; *q != (hex ? 'x' : '#'); --q)
          if (!(hex ? std::isxdigit(static_cast<unsigned char>(*q)) : std::isdigit(static_cast<unsigned char>(*q)))) return false;
        p_ = semi + 1;
      } else {
        ++p_;
      }
    }
    return true;
  }
  void skip_past(const char* end) {
    const char* at = std::strstr(p_, end);
    p_ = at ? at + std::strlen(end) : p_ + std::strlen(p_);
  }
  int line_at(const char* at) const { return 1 + static_cast<int>(std::count(s_, at, '\n')); }
  static std::string name_at(const char* at) {
    std::string name;
    while (name_char(*at) && name.size() < 40) name += *at++;
    return name;
  }

  // name = value, the value quoted or bare; false where TinyXML stops with an error.
  bool attribute() {
    if (!name_start(*p_)) return false;
    while (name_char(*p_)) ++p_;
    skip_space();
    if (*p_ != '=') return false;
    ++p_;
    skip_space();
    if (*p_ == '"' || *p_ == '\'') {
      const char quote = *p_++;
      if (!text_until(quote) || !*p_) return false;
      ++p_;
      return true;
    }
    for (; *p_ && !space(*p_) && *p_ != '/' && *p_ != '>'; ++p_)
      if (*p_ == '"' || *p_ == '\'') return false;
    return *p_ != '\0';
  }

  // After "<": the name, the attributes, then "/>" (0) or ">" (1: an element with content); -1 where
  // TinyXML stops with an error.
  int start_tag() {
    skip_space();
    while (name_char(*p_)) ++p_;
    for (;;) {
      skip_space();
      if (!*p_) return -1;
      if (*p_ == '/') {
        if (p_[1] != '>') return -1;
        p_ += 2;
        return 0;
      }
      if (*p_ == '>') {
        ++p_;
        return 1;
      }
      if (!attribute()) return -1;
    }
  }

  // After "<?xml": version, encoding and standalone read as attributes, other words skipped, up to ">".
  bool declaration() {
    while (*p_) {
      if (*p_ == '>') {
        ++p_;
        return true;
      }
      skip_space();
      if (starts_nocase("version") || starts_nocase("encoding") || starts_nocase("standalone")) {
        if (!attribute()) return false;
      } else {
        while (*p_ && *p_ != '>' && !space(*p_)) ++p_;
      }
    }
    return false;
  }

  // Well-formed UTF-8 up to the first NUL (where TinyXML stops reading).
  void check_utf8() const {
    const auto* u = reinterpret_cast<const unsigned char*>(s_);
    for (std::size_t i = 0; u[i];) {
      const unsigned char c = u[i];
      const int n = c < 0x80 ? 0 : c >= 0xC2 && c <= 0xDF ? 1 : c >= 0xE0 && c <= 0xEF ? 2 : c >= 0xF0 && c <= 0xF4 ? 3 : -1;
      bool ok = n >= 0;
      for (int k = 1; ok && k <= n; ++k) ok = (u[i + k] & 0xC0) == 0x80;
      if (!ok) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02X", c);
        throw ConfigError(source_, line_at(s_ + i), "", std::string("byte ") + hex + " is not UTF-8 text (a URDF is UTF-8)");
      }
      i += static_cast<std::size_t>(n) + 1;
    }
  }

  const char* s_;
  const char* p_ = s_;
  const std::string& source_;
};

// ---- pass 1: the structure, with lines --------------------------------------------------------

struct XmlJoint {
  const TiXmlElement* element = nullptr;
  std::string name, parent, child;
};

struct XmlLink {
  const TiXmlElement* element = nullptr;
  const XmlJoint* parent_joint = nullptr;   // null for the root
  std::vector<const XmlJoint*> child_joints;  // in document order
};

// A Gazebo spring value and the element it was written in.
struct Written {
  double value = 0.0;
  const TiXmlElement* element = nullptr;
};

// Moved, never copied: links and joints point at each other inside the two maps.
struct XmlIndex {
  const TiXmlElement* robot = nullptr;
  std::map<std::string, XmlLink> links;
  std::map<std::string, XmlJoint> joints;
  std::string root;
  std::vector<std::string> bodies;  // every link but the root, parents first
  std::map<std::string, Written> spring_stiffness, spring_reference;  // by joint name
};

const char* text_attribute(const std::string& source, const TiXmlElement* e, const char* attribute,
                           const std::string& what) {
  const char* value = e->Attribute(attribute);
  if (!value || !*value) fail(source, e, what, "<" + e->ValueStr() + "> has no " + attribute + "=\"...\"");
  return value;
}

// The link named by <parent link=...> or <child link=...> of a joint.
std::string joint_link(const std::string& source, const XmlIndex& x, const XmlJoint& j, const char* tag) {
  const std::string what = quoted("joint", j.name);
  const TiXmlElement* e = j.element->FirstChildElement(tag);
  if (!e) fail(source, j.element, what, std::string("has no <") + tag + " link=\"...\"/>");
  const std::string link = text_attribute(source, e, "link", what);
  if (!x.links.count(link)) fail(source, e, what, std::string(tag) + " link \"" + link + "\" does not exist");
  return link;
}

void check_joint_type(const std::string& source, const XmlJoint& j) {
  const std::string what = quoted("joint", j.name);
  const std::string type = text_attribute(source, j.element, "type", what);
  if (type == "revolute" || type == "continuous" || type == "prismatic" || type == "fixed") return;
  if (type == "floating" || type == "planar")
    fail(source, j.element, what,
         "a " + type + " joint is not supported: the base is fixed and every joint has one degree of freedom "
         "(revolute, continuous, prismatic) or none (fixed)");
  fail(source, j.element, what, "unknown joint type \"" + type + "\" (revolute, continuous, prismatic, fixed)");
}

// A Gazebo value: the element's text, one finite number.
double gazebo_number(const std::string& source, const TiXmlElement* e, const std::string& what) {
  std::string text = e->GetText() ? e->GetText() : "";
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  text = first == std::string::npos ? "" : text.substr(first, last - first + 1);
  double x = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), x);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size() || !std::isfinite(x))
    fail(source, e, what, "<" + e->ValueStr() + "> '" + text + "' is not a finite number");
  return x;
}

void read_gazebo_springs(const std::string& source, XmlIndex& x) {
  for (const TiXmlElement* g = x.robot->FirstChildElement("gazebo"); g; g = g->NextSiblingElement("gazebo")) {
    const TiXmlElement* tags[] = {g->FirstChildElement("springStiffness"), g->FirstChildElement("springReference")};
    if (!tags[0] && !tags[1]) continue;  // materials, plugins, ...: not ours
    const char* ref = g->Attribute("reference");
    if (!ref || !*ref) fail(source, g, "gazebo", "a spring needs reference=\"JOINT\"");
    const std::string what = std::string("gazebo reference=\"") + ref + "\"";
    std::vector<std::string> joint_names;
    for (const auto& [name, j] : x.joints) joint_names.push_back(name);
    if (!x.joints.count(ref))
      fail(source, g, what, x.links.count(ref) ? std::string("names a link: springs belong to joints")
                                                : std::string("no joint named \"") + ref + "\"" + format_did_you_mean(ref, joint_names));
    std::map<std::string, Written>* into[] = {&x.spring_stiffness, &x.spring_reference};
    for (int k = 0; k < 2; ++k) {
      const TiXmlElement* e = tags[k];
      if (!e) continue;
      if (e->NextSiblingElement(e->Value())) fail(source, e->NextSiblingElement(e->Value()), what, "<" + e->ValueStr() + "> given twice");
      const auto [it, fresh] = into[k]->try_emplace(ref, Written{gazebo_number(source, e, what), e});
      if (!fresh)
        fail(source, e, what,
             "<" + e->ValueStr() + "> for this joint is already given at line " + std::to_string(row(it->second.element)));
    }
  }
}

XmlIndex index_xml(const std::string& source, const TiXmlDocument& doc) {
  XmlIndex x;
  x.robot = doc.RootElement();
  if (!x.robot) fail(source, nullptr, "", "no XML element (an empty file?)");
  if (x.robot->ValueStr() != "robot")
    fail(source, x.robot, "", "the root element is <" + x.robot->ValueStr() + ">, not <robot>");

  std::vector<std::string> link_order;
  for (const TiXmlElement* e = x.robot->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const std::string name = text_attribute(source, e, "name", "link");
    const auto [it, fresh] = x.links.try_emplace(name, XmlLink{e, nullptr, {}});
    if (!fresh) fail(source, e, quoted("link", name), "defined twice (first at line " + std::to_string(row(it->second.element)) + ")");
    link_order.push_back(name);
  }
  if (x.links.empty()) fail(source, x.robot, "", "no <link> in <robot>");
  // Every link but the root is a body: refused here, before liburdfdom reads them all.
  if (const std::string fault = tree_size_fault(x.links.size() - 1); !fault.empty()) {
    const std::string& past = link_order[static_cast<std::size_t>(kMaxTreeBodies) + 1];
    fail(source, x.links.at(past).element, quoted("link", past), fault);
  }

  for (const TiXmlElement* e = x.robot->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    const std::string name = text_attribute(source, e, "name", "joint");
    const auto [it, fresh] = x.joints.try_emplace(name, XmlJoint{e, name, "", ""});
    if (!fresh) fail(source, e, quoted("joint", name), "defined twice (first at line " + std::to_string(row(it->second.element)) + ")");
    XmlJoint& j = it->second;
    check_joint_type(source, j);
    j.parent = joint_link(source, x, j, "parent");
    j.child = joint_link(source, x, j, "child");
    if (j.parent == j.child) fail(source, e, quoted("joint", name), "joins link \"" + j.parent + "\" to itself");
    XmlLink& child = x.links.at(j.child);
    if (child.parent_joint)
      fail(source, e->FirstChildElement("child"), quoted("joint", name),
           "link \"" + j.child + "\" is already the child of joint \"" + child.parent_joint->name + "\" (line " +
               std::to_string(row(child.parent_joint->element)) + "): a link has one parent");
    child.parent_joint = &j;
    x.links.at(j.parent).child_joints.push_back(&j);
  }

  for (const std::string& name : link_order) {
    if (x.links.at(name).parent_joint) continue;
    if (!x.root.empty())
      fail(source, x.links.at(name).element, quoted("link", name),
           "a second root link (the first is \"" + x.root + "\", line " + std::to_string(row(x.links.at(x.root).element)) +
               "): every link but the root must be the child of a joint");
    x.root = name;
  }
  if (x.root.empty()) fail(source, x.robot, "", "no root link: every link is the child of a joint (a cycle)");

  // Parents first, each link's children in the order of their joints in the file.
  std::vector<std::string> stack{x.root};
  while (!stack.empty()) {
    const std::string link = stack.back();
    stack.pop_back();
    if (link != x.root) x.bodies.push_back(link);
    const auto& children = x.links.at(link).child_joints;
    for (auto it = children.rbegin(); it != children.rend(); ++it) stack.push_back((*it)->child);
  }
  if (x.bodies.size() + 1 != x.links.size())
    for (const std::string& name : link_order)
      if (name != x.root && std::find(x.bodies.begin(), x.bodies.end(), name) == x.bodies.end())
        fail(source, x.links.at(name).element, quoted("link", name),
             "not connected to the root link \"" + x.root + "\": its joints form a cycle");

  read_gazebo_springs(source, x);
  return x;
}

// ---- pass 2: liburdfdom, its console output captured --------------------------------------------

class Capture : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_WARN) return;
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR) ++errors;
    std::string line = text;
    for (char& c : line)
      if (c == '\n' || c == '\r') c = ' ';
    while (!line.empty() && line.back() == ' ') line.pop_back();
    messages.push_back(line);
  }
  std::vector<std::string> messages;
  int errors = 0;
};

struct Urdfdom {
  urdf::ModelInterfaceSharedPtr model;  // null: rejected
  std::vector<std::string> messages;    // its warnings and errors, one line each
  int errors = 0;
  // liburdfdom 3.0 logs an error for a bad <inertial>, <visual> or <collision> and keeps the link (with
  // what it had read): an error message rejects the file as a null model does.
  bool rejected() const { return !model || errors > 0; }
};

// console_bridge's output handler is one global: one parse at a time installs ours.
std::mutex console_mutex;

Urdfdom run_urdfdom(const std::string& xml) {
  const std::lock_guard lock(console_mutex);
  Capture capture;
  struct Installed {
    console_bridge::LogLevel level = console_bridge::getLogLevel();
    explicit Installed(Capture* c) {
      console_bridge::useOutputHandler(c);
      console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
    }
    ~Installed() {
      console_bridge::setLogLevel(level);
      console_bridge::restorePreviousOutputHandler();
    }
    Installed(const Installed&) = delete;
    Installed& operator=(const Installed&) = delete;
  };
  Urdfdom out;
  {
    const Installed installed(&capture);
    try {
      out.model = urdf::parseURDF(xml);
    } catch (const std::exception& e) {
      out.model.reset();
      capture.messages.push_back(e.what());
    }
  }
  out.messages = std::move(capture.messages);
  out.errors = capture.errors;
  return out;
}

std::string joined(const std::vector<std::string>& messages) {
  std::string s;
  for (const auto& m : messages) s += (s.empty() ? "" : "; ") + m;
  return s.empty() ? "rejected without a message" : s;
}

// The part of `element` a liburdfdom message is about (its words), else the element itself.
const TiXmlElement* part_named(const TiXmlElement* element, const std::string& message) {
  static const struct {
    const char* word;
    const char* path[2];
  } kParts[] = {{"origin", {"origin", nullptr}},         {"axis", {"axis", nullptr}},
                {"limit", {"limit", nullptr}},           {"safety", {"safety_controller", nullptr}},
                {"calibration", {"calibration", nullptr}}, {"mimic", {"mimic", nullptr}},
                {"dynamics", {"dynamics", nullptr}},     {"Inertial: mass", {"inertial", "mass"}},
                {"inertia element", {"inertial", "inertia"}}, {"visual", {"visual", nullptr}},
                {"collision", {"collision", nullptr}},   {"vector", {"inertial", "origin"}},
                {"inertial", {"inertial", nullptr}}};
  for (const auto& part : kParts) {
    if (message.find(part.word) == std::string::npos) continue;
    const TiXmlElement* e = element->FirstChildElement(part.path[0]);
    if (e && part.path[1]) e = e->FirstChildElement(part.path[1]);
    if (e) return e;
  }
  return element;
}

// liburdfdom rejected the file: each <material>, <link> and <joint> alone (a joint between two bare
// links) in document order; the first it rejects is the one named, at the line of the part its message
// is about. None alone: the file as a whole (e.g. the robot's version), at <robot>.
[[noreturn]] void fail_urdfdom(const std::string& source, const XmlIndex& x, const std::vector<std::string>& messages) {
  for (const TiXmlElement* e = x.robot->FirstChildElement(); e; e = e->NextSiblingElement()) {
    const std::string tag = e->ValueStr();
    if (tag != "material" && tag != "link" && tag != "joint") continue;
    TiXmlDocument probe;
    TiXmlElement robot("robot");
    robot.SetAttribute("name", "probe");
    robot.InsertEndChild(*e);
    const std::string name = e->Attribute("name") ? e->Attribute("name") : "";
    // A joint needs its two links, a material some link: bare ones (a name, nothing else).
    auto add_bare_link = [&](const std::string& link) {
      TiXmlElement bare("link");
      bare.SetAttribute("name", link.c_str());
      robot.InsertEndChild(bare);
    };
    if (tag == "joint") {
      add_bare_link(x.joints.at(name).parent);
      add_bare_link(x.joints.at(name).child);
    } else if (tag == "material") {
      add_bare_link("probe");
    }
    probe.InsertEndChild(robot);
    TiXmlPrinter printer;
    probe.Accept(&printer);
    const Urdfdom alone = run_urdfdom(printer.CStr());
    if (!alone.rejected()) continue;
    const std::string message = joined(alone.messages);
    fail(source, part_named(e, message), quoted(tag.c_str(), name), "liburdfdom: " + message);
  }
  fail(source, x.robot, "robot", "liburdfdom: " + joined(messages));
}

// ---- pass 3: the tree ---------------------------------------------------------------------------

Vec3 vec(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }
Mat3 matrix(const urdf::Rotation& r) { return Eigen::Quaterniond(r.w, r.x, r.y, r.z).toRotationMatrix(); }

std::string note(const std::string& source, const TiXmlElement* at, const std::string& what, const std::string& text) {
  return ConfigError(source, row(at), what, text).what();
}

// The element `tag` of `e`, else `e` (for a line).
const TiXmlElement* part(const TiXmlElement* e, const char* tag) {
  const TiXmlElement* p = e->FirstChildElement(tag);
  return p ? p : e;
}

}  // namespace

TreeDescription parse_urdf(const std::string& xml, const std::string& source) {
  DepthScan(xml, source).run();
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error()) throw ConfigError(source, doc.ErrorRow(), "", std::string("malformed XML: ") + doc.ErrorDesc());
  const XmlIndex x = index_xml(source, doc);

  const Urdfdom parsed = run_urdfdom(xml);
  if (parsed.rejected()) fail_urdfdom(source, x, parsed.messages);
  const urdf::ModelInterface& model = *parsed.model;

  TreeDescription d;
  d.base = x.root;
  for (const std::string& m : parsed.messages) d.notes.push_back(source + ": liburdfdom: " + m);
  const XmlLink& root = x.links.at(x.root);
  if (const auto inertial = model.getLink(x.root)->inertial)
    d.notes.push_back(note(source, root.element->FirstChildElement("inertial"), quoted("link", x.root),
                           "the root link is the fixed base: its inertial (" + fmt(inertial->mass) + " kg) is ignored"));

  std::map<std::string, int> index;  // link -> body
  for (const std::string& name : x.bodies) {
    const XmlLink& xl = x.links.at(name);
    const XmlJoint& xj = *xl.parent_joint;
    const TiXmlElement* je = xj.element;
    const std::string jwhat = quoted("joint", xj.name), lwhat = quoted("link", name);
    const urdf::Joint& j = *model.getJoint(xj.name);
    const urdf::Link& l = *model.getLink(name);

    BodySpec b;
    JointInfo info;
    b.name = name;
    info.name = xj.name;
    b.parent = xj.parent == x.root ? -1 : index.at(xj.parent);
    switch (j.type) {
      case urdf::Joint::REVOLUTE:
      case urdf::Joint::CONTINUOUS: b.joint = JointType::kRevolute; break;
      case urdf::Joint::PRISMATIC: b.joint = JointType::kPrismatic; break;
      case urdf::Joint::FIXED: b.joint = JointType::kFixed; break;
      default: fail(source, je, jwhat, "joint type not supported");  // pass 1 let only these four through
    }
    const bool moving = b.joint != JointType::kFixed;
    b.position = vec(j.parent_to_joint_origin_transform.position);
    b.rotation = matrix(j.parent_to_joint_origin_transform.rotation);

    if (moving) {
      b.axis = vec(j.axis);
      if (b.axis.norm() == 0.0) fail(source, part(je, "axis"), jwhat, "axis is zero");
      if (j.limits) {
        const TiXmlElement* le = part(je, "limit");
        if (j.type != urdf::Joint::CONTINUOUS) {  // a continuous joint has no position limits
          info.lower = j.limits->lower;
          info.upper = j.limits->upper;
          if (info.lower > info.upper)
            fail(source, le, jwhat, "limit upper " + fmt(info.upper) + " is below lower " + fmt(info.lower));
        }
        info.effort = j.limits->effort;
        info.velocity = j.limits->velocity;
        if (info.effort < 0.0) fail(source, le, jwhat, "limit effort " + fmt(info.effort) + " is negative");
        if (info.velocity < 0.0) fail(source, le, jwhat, "limit velocity " + fmt(info.velocity) + " is negative");
      }
    }
    if (j.dynamics) {
      const TiXmlElement* de = part(je, "dynamics");
      if (!moving) {
        d.notes.push_back(note(source, de, jwhat, "a fixed joint has no damping or friction: <dynamics> ignored"));
      } else {
        b.damping = j.dynamics->damping;
        info.friction = j.dynamics->friction;
        if (b.damping < 0.0) fail(source, de, jwhat, "dynamics damping " + fmt(b.damping) + " is negative");
        if (info.friction < 0.0) fail(source, de, jwhat, "dynamics friction " + fmt(info.friction) + " is negative");
      }
    }
    const auto stiffness = x.spring_stiffness.find(xj.name), reference = x.spring_reference.find(xj.name);
    if (!moving && (stiffness != x.spring_stiffness.end() || reference != x.spring_reference.end())) {
      const auto& w = stiffness != x.spring_stiffness.end() ? stiffness->second : reference->second;
      d.notes.push_back(note(source, w.element->Parent()->ToElement(), jwhat,
                             "a fixed joint has no spring: its Gazebo spring is ignored"));
    } else {
      if (stiffness != x.spring_stiffness.end()) {
        b.stiffness = stiffness->second.value;
        if (b.stiffness < 0.0)
          fail(source, stiffness->second.element, jwhat, "springStiffness " + fmt(b.stiffness) + " is negative");
      }
      if (reference != x.spring_reference.end()) b.spring_reference = reference->second.value;
    }
    if (j.mimic)
      d.notes.push_back(note(source, part(je, "mimic"), jwhat,
                             "<mimic joint=\"" + j.mimic->joint_name + "\"> ignored: the joints move independently"));

    if (l.inertial) {
      const TiXmlElement* ie = part(xl.element, "inertial");
      const urdf::Inertial& in = *l.inertial;
      if (!(in.mass >= 0.0)) fail(source, part(ie, "mass"), lwhat, "mass " + fmt(in.mass) + " kg is negative");
      Mat3 I;  // about the COM in the inertial frame's axes
      I << in.ixx, in.ixy, in.ixz,
           in.ixy, in.iyy, in.iyz,
           in.ixz, in.iyz, in.izz;
      const Mat3 R = matrix(in.origin.rotation);  // the inertial frame in the link frame
      b.mass = in.mass;
      b.com = vec(in.origin.position);
      b.inertia = R * I * R.transpose();
      if (const std::string fault = inertia_fault(b); !fault.empty()) fail(source, part(ie, "inertia"), lwhat, fault);
    }
    if (const std::string fault = joint_fault(b); !fault.empty()) fail(source, je, jwhat, fault);
    index[name] = static_cast<int>(d.spec.bodies.size());
    d.spec.bodies.push_back(std::move(b));
    d.joints.push_back(std::move(info));
  }
  if (const std::string fault = finish_description(d); !fault.empty()) fail(source, x.robot, "robot", fault);
  return d;
}

void apply_urdf_sidecar(TreeDescription& d, const YAML::Node& doc, const std::string& source) {
  LineMap lines;
  YamlReader top(doc, source, "", &lines);
  if (!doc || doc.IsNull()) top.fail("joints", "the file is empty");
  top.read_units_check();
  const YAML::Node map = top.raw("joints"), link_map = top.raw("links");
  YamlReader joints = top.child("joints");
  YamlReader links = top.child("links");
  top.finish();
  if (!top.has("joints") && !top.has("links")) top.fail("joints", "missing: a sidecar gives `joints`, `links` or both");
  if (top.has("joints"))
    for (const auto& kv : map) {
      const std::string name = kv.first.Scalar();
      const auto it = std::find_if(d.joints.begin(), d.joints.end(), [&](const JointInfo& j) { return j.name == name; });
      if (it == d.joints.end())
        joints.fail(name, "no joint named '" + name + "' in the URDF" + format_did_you_mean(name, list_joint_names(d)));
      BodySpec& body = d.spec.bodies.at(static_cast<std::size_t>(it - d.joints.begin()));
      if (body.joint == JointType::kFixed)
        joints.fail(name, "joint '" + name + "' is fixed: it has no degree of freedom for these values");
      YamlReader joint = joints.child(name);
      read_joint_springs(joint, body);
      joint.finish();
      if (const std::string fault = joint_fault(body); !fault.empty()) joints.fail(name, fault);
    }
  joints.finish();

  // Flexible links: read first, then made flexible last body first (so the others' indices hold).
  struct Flexible {
    int body;
    std::string name;
    FlexibleLinkSpec link;
  };
  std::vector<Flexible> flexible;
  if (top.has("links"))
    for (const auto& kv : link_map) {
      const std::string name = kv.first.Scalar();
      if (name == d.base) links.fail(name, "link '" + name + "' is the root link, the fixed base: it cannot be flexible");
      const auto it = d.body_index.find(name);
      if (it == d.body_index.end())
        links.fail(name, "no link named '" + name + "' in the URDF" + format_did_you_mean(name, list_body_names(d)));
      YamlReader link = links.child(name);
      link.only({"flexible"});
      YamlReader block = link.child("flexible", true);
      link.finish();
      flexible.push_back({it->second, name, read_flexible_block(block)});
      const BodySpec& b = d.spec.bodies.at(static_cast<std::size_t>(it->second));
      if (b.mass > 0.0 || b.inertia.cwiseAbs().maxCoeff() > 0.0) {
        const std::string key = links.full_key(name) + ".flexible";
        d.notes.push_back(ConfigError(source, lines.count(key) ? lines.at(key) : 0, key,
                                      "link \"" + name + "\": its <inertial> (" + fmt(b.mass) +
                                          " kg) is replaced by the flexible beam")
                              .what());
      }
    }
  links.finish();
  std::sort(flexible.begin(), flexible.end(), [](const Flexible& a, const Flexible& b) { return a.body > b.body; });
  for (const Flexible& f : flexible)
    if (const std::string fault = make_flexible(d, f.body, f.link); !fault.empty()) links.fail(f.name, fault);
  if (const std::string fault = finish_description(d); !fault.empty())
    top.fail(flexible.empty() ? "joints" : "links", fault);
}

std::vector<KeyDoc> urdf_sidecar_keys() {
  std::vector<KeyDoc> out{{"joints", "", "no", "none"}};  // and `units_check`, in the tree's table
  for (KeyDoc& k : joint_spring_keys("joints.NAME.")) out.push_back(std::move(k));
  out.push_back({"links", "", "no", "none"});
  out.push_back({"links.NAME.flexible", "", "yes", ""});
  for (KeyDoc& k : flexible_keys("links.NAME.flexible.")) out.push_back(std::move(k));
  return out;
}

TreeDescription load_urdf(const std::string& path, const std::string& sidecar) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path, 0, "", "cannot open file");
  std::stringstream text;
  text << in.rdbuf();
  TreeDescription d = parse_urdf(text.str(), path);
  if (!sidecar.empty()) apply_urdf_sidecar(d, load_yaml_file(sidecar), sidecar);
  return d;
}

}  // namespace ff
