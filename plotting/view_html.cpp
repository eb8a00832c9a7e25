#include "plotting/view_html.hpp"

#include "common/files.hpp"
#include "common/text.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <span>
#include <stdexcept>
#include <string_view>
#include <type_traits>
#include <utility>

// The page's template, its module and the vendored three.js (plotting/view/), compiled in by
// cmake/embed.cmake.
namespace ff::view_assets {
extern const std::string_view view_html, view_js, three_core, three_module, orbit_controls, three_license;
}

namespace ff {
namespace {

// ---- Checks of the scene.

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument("view: " + what); }

std::string variant_name(const ViewVariant& v, std::size_t i) {
  return "variant " + std::to_string(i) + (v.label.empty() ? "" : " (" + v.label + ")");
}

void check_scene(const ViewScene& s) {
  if (!s.up.allFinite() || s.up.norm() == 0) fail("up must be a finite, non-zero vector");
  if (s.variants.empty()) fail("the scene has no variants");
  const int nc = int(s.capsules.size()), ns = int(s.shapes.size());
  for (const ViewCapsule& c : s.capsules)
    if (!std::isfinite(c.radius) || c.radius < 0) fail("capsule '" + c.name + "': radius must be finite and >= 0");
  static const std::vector<std::string> types = {"box", "sphere", "cylinder", "capsule", "bore", "plane", "mesh"};
  for (const ViewShape& sh : s.shapes) {
    const std::string name = "shape '" + sh.name + "'";
    if (std::find(types.begin(), types.end(), sh.type) == types.end()) fail(name + ": unknown type '" + sh.type + "'");
    if (!sh.pose.allFinite() || !sh.size.allFinite() || !std::isfinite(sh.radius) || !std::isfinite(sh.length))
      fail(name + ": pose, size, radius and length must be finite");
    for (const auto& tri : sh.triangles)
      for (int i : tri)
        if (i < 0 || i >= int(sh.vertices.size())) fail(name + ": triangle index " + std::to_string(i) + " out of range");
  }
  for (std::size_t i = 0; i < s.variants.size(); ++i) {
    const ViewVariant& v = s.variants[i];
    const std::string name = variant_name(v, i);
    const std::size_t n = v.t.size();
    if (n == 0) fail(name + ": no samples");
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(v.t[k]) || (k > 0 && !(v.t[k] > v.t[k - 1])))
        fail(name + ": times must be finite and increasing (sample " + std::to_string(k) + ")");
    const auto sized = [&](const std::vector<float>& a, std::size_t per, const char* what, bool may_be_empty) {
      if (a.size() != n * per && !(may_be_empty && a.empty()))
        fail(name + ": " + what + " has " + std::to_string(a.size()) + " values, not " + std::to_string(n * per) + " (" +
             std::to_string(n) + " samples x " + std::to_string(per) + ")");
    };
    sized(v.ends, std::size_t(nc) * 6, "ends", false);
    sized(v.rigid_ends, std::size_t(nc) * 6, "rigid_ends", true);
    sized(v.tool, 3, "tool", true);
    if (v.worst_capsule < -1 || v.worst_capsule >= nc) fail(name + ": worst_capsule out of range");
    if (v.worst_shape >= ns || v.worst_shape < -(nc + 1)) fail(name + ": worst_shape out of range");
  }
}

// ---- JSON, written for a <script> element: '<' and '>' in strings escaped, so no "</script" can occur.

void put_string(std::string& out, std::string_view s) {
  out += '"';
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == '<' || c == '>') {
          char u[8];
          std::snprintf(u, sizeof u, "\\u%04x", static_cast<unsigned char>(c));
          out += u;
        } else {
          out += c;
        }
    }
  }
  out += '"';
}

// A number: doubles exactly (shortest round trip), floats to 6 significant digits, ints; non-finite as null.
template <class T>
void put_number(std::string& out, T x) {
  if (!std::isfinite(double(x))) {
    out += "null";
    return;
  }
  char buf[32];
  std::to_chars_result r;
  if constexpr (std::is_same_v<T, float>)
    r = std::to_chars(buf, buf + sizeof buf, x, std::chars_format::general, 6);
  else
    r = std::to_chars(buf, buf + sizeof buf, x);
  out.append(buf, r.ptr);
}

template <class Range>
void put_array(std::string& out, const Range& xs) {
  out += '[';
  bool first = true;
  for (const auto x : xs) {
    if (!first) out += ',';
    first = false;
    put_number(out, x);
  }
  out += ']';
}

// The rows `rows` (each `per` values) of a in one flat array, or [] for an empty a.
template <class T>
void put_rows(std::string& out, const std::vector<T>& a, const std::vector<std::size_t>& rows, std::size_t per) {
  out += '[';
  for (std::size_t r = 0; r < rows.size() && !a.empty(); ++r)
    for (std::size_t j = 0; j < per; ++j) {
      if (r || j) out += ',';
      put_number(out, a[rows[r] * per + j]);
    }
  out += ']';
}

// A JSON object written member by member: key() starts a member and returns the text to write its value to.
class Object {
 public:
  explicit Object(std::string& out) : out_(out) { out_ += '{'; }
  ~Object() { out_ += '}'; }
  std::string& key(const char* name) {
    out_ += first_ ? "\"" : ",\"";
    first_ = false;
    out_ += name;
    return out_ += "\":";
  }

 private:
  std::string& out_;
  bool first_ = true;
};

// The samples kept of n: at most `most`, evenly in index with the first and the last, and the one nearest
// the time `keep` (if finite).
std::vector<std::size_t> thinned(const std::vector<double>& t, std::size_t most, double keep) {
  const std::size_t n = t.size();
  std::vector<std::size_t> rows;
  if (n <= most) {
    for (std::size_t i = 0; i < n; ++i) rows.push_back(i);
    return rows;
  }
  for (std::size_t k = 0; k < most; ++k) rows.push_back(std::size_t(std::llround(double(k) * double(n - 1) / double(most - 1))));
  if (std::isfinite(keep)) {
    const std::size_t i = std::size_t(std::lower_bound(t.begin(), t.end(), keep) - t.begin());
    const std::size_t nearest = i == n ? n - 1 : i > 0 && keep - t[i - 1] < t[i] - keep ? i - 1 : i;
    rows.push_back(nearest);
    std::sort(rows.begin(), rows.end());
  }
  rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
  return rows;
}

static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float) && sizeof(std::array<int, 3>) == 3 * sizeof(int));

// The scene as JSON (the page's view.js reads it), appended to out.
void put_scene(std::string& out, const ViewScene& s) {
  Object scene(out);
  put_string(scene.key("title"), s.title);
  put_array(scene.key("up"), s.up);
  scene.key("shapes") += '[';
  for (std::size_t i = 0; i < s.shapes.size(); ++i) {
    const ViewShape& sh = s.shapes[i];
    if (i) out += ',';
    Object o(out);
    put_string(o.key("name"), sh.name);
    put_string(o.key("type"), sh.type);
    const Eigen::Matrix<double, 4, 4, Eigen::RowMajor> pose = sh.pose;  // row-major, as THREE.Matrix4.set takes it
    put_array(o.key("pose"), std::span<const double>(pose.data(), 16));
    put_array(o.key("size"), sh.size);
    put_number(o.key("radius"), sh.radius);
    put_number(o.key("length"), sh.length);
    put_array(o.key("vertices"), std::span<const float>(sh.vertices.empty() ? nullptr : sh.vertices[0].data(), 3 * sh.vertices.size()));
    put_array(o.key("triangles"), std::span<const int>(sh.triangles.empty() ? nullptr : sh.triangles[0].data(), 3 * sh.triangles.size()));
  }
  out += ']';
  scene.key("capsules") += '[';
  for (std::size_t i = 0; i < s.capsules.size(); ++i) {
    if (i) out += ',';
    Object o(out);
    put_string(o.key("name"), s.capsules[i].name);
    put_number(o.key("radius"), s.capsules[i].radius);
  }
  out += ']';
  scene.key("variants") += '[';
  const std::size_t ghosts = s.variants.size() - 1;
  const std::size_t ghost_frames = ghosts ? std::clamp<std::size_t>(kViewMaxGhostFrames / ghosts, kViewMinGhostFrames, kViewMaxFrames) : 0;
  const std::size_t per = 6 * s.capsules.size();
  for (std::size_t i = 0; i < s.variants.size(); ++i) {
    const ViewVariant& v = s.variants[i];
    const std::vector<std::size_t> rows = thinned(v.t, i ? ghost_frames : kViewMaxFrames, v.worst_time);
    if (i) out += ',';
    Object o(out);
    put_string(o.key("label"), v.label);
    put_rows(o.key("t"), v.t, rows, 1);
    put_rows(o.key("ends"), v.ends, rows, per);
    put_rows(o.key("rigid_ends"), v.rigid_ends == v.ends ? std::vector<float>{} : v.rigid_ends, rows, per);
    put_rows(o.key("tool"), v.tool, rows, 3);
    put_number(o.key("min_clearance"), v.min_clearance);
    put_number(o.key("worst_capsule"), v.worst_capsule);
    put_number(o.key("worst_shape"), v.worst_shape);
    put_number(o.key("worst_time"), v.worst_time);
    put_array(o.key("worst_a"), v.worst_a);
    put_array(o.key("worst_b"), v.worst_b);
  }
  out += ']';
}

// ---- The page.

}  // namespace

std::string html_escape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

namespace {

// JavaScript inside a <script> element: "</script" and "<!--" would end or confuse it; "<\/" and "<\!"
// mean the same in JavaScript's strings, regular expressions and comments (the only places they occur).
std::string script_safe(std::string_view js) {
  std::string out;
  out.reserve(js.size());
  for (std::size_t i = 0; i < js.size(); ++i) {
    out += js[i];
    if (js[i] != '<') continue;
    std::string next(js.substr(i + 1, 7));
    std::transform(next.begin(), next.end(), next.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (next == "/script" || next.starts_with("!--")) out += '\\';
  }
  return out;
}

}  // namespace

void write_view_html(const ViewScene& scene, const std::string& path) {
  check_scene(scene);
  std::string json;
  put_scene(json, scene);
  write_file_atomic(path, fill_template(view_assets::view_html, {
                                   {"@TITLE@", html_escape(scene.title)},
                                   {"@LICENSE@", std::string(view_assets::three_license)},
                                   {"@THREE_CORE@", script_safe(view_assets::three_core)},
                                   {"@THREE_MODULE@", script_safe(view_assets::three_module)},
                                   {"@ORBIT_CONTROLS@", script_safe(view_assets::orbit_controls)},
                                   {"@SCENE@", std::move(json)},
                                   {"@VIEW_JS@", script_safe(view_assets::view_js)},
                               }));
}

}  // namespace ff
