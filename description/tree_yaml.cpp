// Tree YAML (tree_yaml.hpp). Each block's keys are one field table below: the reader reads, bounds and
// requires from it, and tree_yaml_keys() lists it for the docs test (tests/description/tree_yaml_test.cpp).
#include "description/tree_yaml.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <variant>

#include "common/closest.hpp"
#include "common/units_check.hpp"
#include "common/field_table.hpp"
#include "common/errors.hpp"
#include "multibody/flexible_link.hpp"
#include "multibody/limits.hpp"

namespace ff {

namespace {

constexpr const char* kDefaultJointType = "revolute";

// The blocks as written, before they become a BodySpec.
struct BodyBlock {
  std::string name, parent;
};
struct RigidBlock {           // a rigid body's mass (a flexible body's comes from its beam)
  double mass = 0.0;          // kg
  Vec3 com = Vec3::Zero();    // m, body frame
};
struct JointBlock {
  std::string name;           // default: the body's name
  std::string type = kDefaultJointType;
  Vec3 axis = Vec3::UnitZ();  // joint frame
  Vec3 position = Vec3::Zero();  // m, parent frame
  Vec3 rpy = Vec3::Zero();    // rad, fixed-axis roll, pitch, yaw in the parent frame
  double lower = -JointInfo::kNone, upper = JointInfo::kNone, effort = JointInfo::kNone,
         velocity = JointInfo::kNone, friction = 0.0;
};
struct InertiaBlock {
  double ixx = 0.0, iyy = 0.0, izz = 0.0, ixy = 0.0, ixz = 0.0, iyz = 0.0;  // kg·m², about the COM, body axes
};

const std::array<Field<TreeSpec>, 1> kTopFields{{
    {.key = "gravity", .member = &TreeSpec::gravity, .unit = "m/s²"},
}};

const std::array<Field<BodyBlock>, 2> kBodyFields{{
    {.key = "name", .member = &BodyBlock::name, .required = true},
    {.key = "parent", .member = &BodyBlock::parent, .required = true},
}};

const std::array<Field<RigidBlock>, 2> kRigidFields{{
    {.key = "mass", .member = &RigidBlock::mass, .unit = "kg", .required = true, .bound = Bound::kNonNegative},
    {.key = "com", .member = &RigidBlock::com, .unit = "m"},
}};

const std::array<Field<JointBlock>, 10> kJointFields{{
    {.key = "name", .member = &JointBlock::name, .fallback = "the body's name"},
    {.key = "type", .member = &JointBlock::type, .fallback = kDefaultJointType},
    {.key = "axis", .member = &JointBlock::axis, .bound = Bound::kNonZero, .moving_only = true},
    {.key = "position", .member = &JointBlock::position, .unit = "m"},
    {.key = "rpy", .member = &JointBlock::rpy, .unit = "rad"},
    {.key = "lower", .member = &JointBlock::lower, .unit = "rad (m)", .moving_only = true},
    {.key = "upper", .member = &JointBlock::upper, .unit = "rad (m)", .moving_only = true},
    {.key = "effort", .member = &JointBlock::effort, .unit = "N·m (N)", .bound = Bound::kNonNegative, .moving_only = true},
    {.key = "velocity", .member = &JointBlock::velocity, .unit = "rad/s (m/s)", .bound = Bound::kNonNegative,
     .moving_only = true},
    {.key = "friction", .member = &JointBlock::friction, .unit = "N·m (N)", .bound = Bound::kNonNegative,
     .moving_only = true},
}};

// The passive joint keys go straight into the BodySpec (shared with the URDF sidecar).
const std::array<Field<BodySpec>, 4> kSpringFields{{
    {.key = "armature", .member = &BodySpec::armature, .unit = "kg·m² (kg)", .bound = Bound::kNonNegative,
     .moving_only = true},
    {.key = "stiffness", .member = &BodySpec::stiffness, .unit = "N·m/rad (N/m)", .bound = Bound::kNonNegative,
     .moving_only = true},
    {.key = "damping", .member = &BodySpec::damping, .unit = "N·m·s/rad (N·s/m)", .bound = Bound::kNonNegative,
     .moving_only = true},
    {.key = "spring_reference", .member = &BodySpec::spring_reference, .unit = "rad (m)", .moving_only = true},
}};

const std::array<Field<InertiaBlock>, 6> kInertiaFields{{
    {.key = "ixx", .member = &InertiaBlock::ixx, .unit = "kg·m²", .required = true},
    {.key = "iyy", .member = &InertiaBlock::iyy, .unit = "kg·m²", .required = true},
    {.key = "izz", .member = &InertiaBlock::izz, .unit = "kg·m²", .required = true},
    {.key = "ixy", .member = &InertiaBlock::ixy, .unit = "kg·m²"},
    {.key = "ixz", .member = &InertiaBlock::ixz, .unit = "kg·m²"},
    {.key = "iyz", .member = &InertiaBlock::iyz, .unit = "kg·m²"},
}};

// The flexible block (multibody/flexible_link.hpp) as written: its section, payload and inertia go
// into the BeamSection, TipPayload and an InertiaBlock.
struct FlexibleBlock {
  double length = 0.0;          // L, m, along the body frame's +x from its origin
  int segments = 6;             // N
  double stiffness_factor = 1.0;  // kappa
  double damping_time = 0.0;    // beta, s
  bool torsion = true;
  bool planar = false;
};
struct PayloadBlock {
  double mass = 0.0;            // kg
  Vec3 com = Vec3::Zero();      // m, from the tip point, tip segment axes
};

const std::array<Field<FlexibleBlock>, 6> kFlexibleFields{{
    {.key = "length", .member = &FlexibleBlock::length, .unit = "m", .required = true, .bound = Bound::kPositive},
    {.key = "segments", .member = &FlexibleBlock::segments, .bound = Bound::kPositive},
    {.key = "stiffness_factor", .member = &FlexibleBlock::stiffness_factor, .bound = Bound::kPositive},
    {.key = "damping_time", .member = &FlexibleBlock::damping_time, .unit = "s", .bound = Bound::kNonNegative},
    {.key = "torsion", .member = &FlexibleBlock::torsion},
    {.key = "planar", .member = &FlexibleBlock::planar},
}};

constexpr const char* kTorsionOnly = "required with torsion";
const std::array<Field<BeamSection>, 7> kSectionFields{{
    {.key = "E", .member = &BeamSection::youngs_modulus, .unit = "Pa", .required = true, .bound = Bound::kModulus},
    {.key = "G", .member = &BeamSection::shear_modulus, .unit = "Pa", .bound = Bound::kModulus,
     .fallback = kTorsionOnly},
    {.key = "density", .member = &BeamSection::density, .unit = "kg/m³", .required = true, .bound = Bound::kDensity},
    {.key = "area", .member = &BeamSection::area, .unit = "m²", .required = true, .bound = Bound::kPositive},
    {.key = "I_y", .member = &BeamSection::second_moment_y, .unit = "m⁴", .required = true, .bound = Bound::kPositive},
    {.key = "I_z", .member = &BeamSection::second_moment_z, .unit = "m⁴", .required = true, .bound = Bound::kPositive},
    {.key = "J", .member = &BeamSection::torsion_constant, .unit = "m⁴", .bound = Bound::kPositive,
     .fallback = kTorsionOnly},
}};

const std::array<Field<PayloadBlock>, 2> kPayloadFields{{
    {.key = "mass", .member = &PayloadBlock::mass, .unit = "kg", .bound = Bound::kNonNegative},
    {.key = "com", .member = &PayloadBlock::com, .unit = "m"},
}};

// A fixed joint has no coordinate: its dof-only keys are mistakes.
template <class T, std::size_t N>
void reject_moving_only(const YamlReader& r, const std::array<Field<T>, N>& fields) {
  for (const Field<T>& f : fields)
    if (f.moving_only && r.has(f.key)) r.fail(f.key, "a fixed joint has no degree of freedom: remove this key");
}

JointType parse_joint_type(const YamlReader& joint, const std::string& type) {
  if (type == "revolute") return JointType::kRevolute;
  if (type == "prismatic") return JointType::kPrismatic;
  if (type == "fixed") return JointType::kFixed;
  joint.fail("type", "unknown joint type '" + type + "' (revolute, prismatic or fixed)");
}

struct Named {
  int index;
  int line;
};

}  // namespace

FlexibleLinkSpec read_flexible_block(YamlReader& r) {
  FlexibleBlock fb;
  read_present(r, kFlexibleFields, fb);
  if (fb.segments > kMaxFlexibleSegments)
    r.fail("segments", "must be <= " + std::to_string(kMaxFlexibleSegments) + " (a flexible link's limit), got " +
                           std::to_string(fb.segments));
  FlexibleLinkSpec link;
  YamlReader sr = r.child("section");
  read_present(sr, kSectionFields, link.section);
  YamlReader pr = r.child("payload");
  PayloadBlock pb;
  read_present(pr, kPayloadFields, pb);
  YamlReader ir = pr.child("inertia");
  InertiaBlock ib;
  read_present(ir, kInertiaFields, ib);
  ir.finish();
  pr.finish();
  sr.finish();
  r.finish();
  require(r, kFlexibleFields);
  if (!r.has("section")) r.fail_missing("section");
  require(sr, kSectionFields);
  if (fb.torsion && !fb.planar)
    for (const char* key : {"G", "J"})
      if (!sr.has(key)) sr.fail(key, "missing: required with torsion (or set torsion: false or planar: true)");
  if (pr.has("inertia")) require(ir, kInertiaFields);
  link.length = fb.length;
  link.segments = fb.segments;
  link.stiffness_factor = fb.stiffness_factor;
  link.damping_time = fb.damping_time;
  link.torsion = fb.torsion;
  link.planar = fb.planar;
  link.payload.mass = pb.mass;
  link.payload.com_offset = pb.com;
  link.payload.inertia << ib.ixx, ib.ixy, ib.ixz,
                          ib.ixy, ib.iyy, ib.iyz,
                          ib.ixz, ib.iyz, ib.izz;
  // append_flexible_link's payload checks (the rest are the bounds above), at the inertia's line.
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(link.payload.inertia, Eigen::EigenvaluesOnly);
  if (eig.eigenvalues()[0] < -1e-12 * std::max(link.payload.inertia.cwiseAbs().maxCoeff(), 1e-300))
    pr.fail("inertia", "is not positive semi-definite");
  return link;
}

std::vector<KeyDoc> flexible_keys(const std::string& prefix) {
  std::vector<KeyDoc> out;
  add_keys(out, prefix, kFlexibleFields);
  out.push_back({prefix + "section", "", "yes", ""});
  add_keys(out, prefix + "section.", kSectionFields);
  out.push_back({prefix + "payload", "", "no", "none"});
  add_keys(out, prefix + "payload.", kPayloadFields);
  out.push_back({prefix + "payload.inertia", "kg·m²", "no", "zero"});
  add_keys(out, prefix + "payload.inertia.", kInertiaFields);
  return out;
}

void read_joint_springs(YamlReader& r, BodySpec& body) { read_present(r, kSpringFields, body); }

std::vector<KeyDoc> joint_spring_keys(const std::string& prefix) {
  std::vector<KeyDoc> out;
  add_keys(out, prefix, kSpringFields);
  return out;
}

std::vector<KeyDoc> tree_yaml_keys() {
  std::vector<KeyDoc> out;
  add_keys(out, "", kTopFields);
  out.push_back(kUnitsCheckKey);
  out.push_back({"bodies", "", "yes", ""});
  add_keys(out, "bodies[i].", kBodyFields);
  add_keys(out, "bodies[i].", kRigidFields);
  out.push_back({"bodies[i].joint", "", "yes", ""});
  add_keys(out, "bodies[i].joint.", kJointFields);
  add_keys(out, "bodies[i].joint.", kSpringFields);
  out.push_back({"bodies[i].inertia", "kg·m²", "no", "zero"});
  add_keys(out, "bodies[i].inertia.", kInertiaFields);
  out.push_back({"bodies[i].flexible", "", "no", "none"});
  for (KeyDoc& k : flexible_keys("bodies[i].flexible.")) out.push_back(std::move(k));
  return out;
}

TreeDescription parse_tree_yaml(const YAML::Node& doc, const std::string& source) {
  LineMap lines;
  YamlReader top(doc, source, "", &lines);
  if (!doc || doc.IsNull()) top.fail("bodies", "the file is empty");
  TreeDescription d;
  d.base = "base";
  top.read_units_check();
  read_present(top, kTopFields, d.spec);
  const YAML::Node list = top.raw("bodies");
  std::vector<YamlReader> bodies = top.sequence("bodies");
  top.finish();
  if (!top.has("bodies")) top.fail_missing("bodies");
  if (bodies.empty()) top.fail("bodies", "expected a list of at least one body");
  if (const std::string fault = tree_size_fault(bodies.size()); !fault.empty()) top.fail("bodies", fault);

  // Every name in the list, for "defined later" (the first of a name; a second is an error below).
  std::map<std::string, Named> listed;
  for (std::size_t i = 0; i < list.size(); ++i)
    if (list[i].IsMap() && list[i]["name"] && list[i]["name"].IsScalar())
      listed.try_emplace(list[i]["name"].Scalar(), Named{static_cast<int>(i), list[i]["name"].Mark().line + 1});

  std::map<std::string, Named> body_names, joint_names;  // the bodies read so far
  std::vector<std::pair<int, FlexibleLinkSpec>> flexible;  // made flexible once every body is read
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const int i = static_cast<int>(k);
    YamlReader& r = bodies[k];
    BodyBlock bb;
    read_present(r, kBodyFields, bb);
    RigidBlock rb;
    read_present(r, kRigidFields, rb);
    YamlReader jr = r.child("joint");
    JointBlock jb;
    read_present(jr, kJointFields, jb);
    BodySpec b;
    read_present(jr, kSpringFields, b);
    YamlReader ir = r.child("inertia");
    InertiaBlock ib;
    read_present(ir, kInertiaFields, ib);
    YamlReader fr = r.child("flexible");
    jr.finish();
    ir.finish();
    r.finish();
    require(r, kBodyFields);
    if (r.has("flexible")) {
      for (const char* key : {"mass", "com", "inertia"})
        if (r.has(key)) r.fail(key, "a flexible body's mass is its beam's: give `flexible` or `mass`, not both");
    } else {
      require(r, kRigidFields);
    }
    if (!r.has("joint")) r.fail_missing("joint");
    require(jr, kJointFields);
    if (r.has("inertia")) require(ir, kInertiaFields);
    if (r.has("flexible")) flexible.emplace_back(i, read_flexible_block(fr));

    b.name = bb.name;
    if (b.name == "base") r.fail("name", "'base' names the fixed base; a body needs another name");
    if (const auto it = body_names.find(b.name); it != body_names.end())
      r.fail("name", "'" + b.name + "' is already the name of bodies[" + std::to_string(it->second.index) + "] (line " +
                         std::to_string(it->second.line) + ")");
    body_names.emplace(b.name, Named{i, r.line()});

    if (bb.parent == "base") {
      b.parent = -1;
    } else if (const auto it = body_names.find(bb.parent); it != body_names.end() && it->second.index < i) {
      b.parent = it->second.index;
    } else if (const auto later = listed.find(bb.parent); later != listed.end()) {
      r.fail("parent", "'" + bb.parent + "' is defined later (bodies[" + std::to_string(later->second.index) +
                           "], line " + std::to_string(later->second.line) + "): list a parent before its children");
    } else {
      std::vector<std::string> earlier{"base"};
      for (const auto& [name, at] : body_names)
        if (at.index < i) earlier.push_back(name);
      r.fail("parent", "no body named '" + bb.parent + "'" + format_did_you_mean(bb.parent, earlier) +
                           " (a parent is `base` or the name of an earlier body)");
    }

    b.joint = parse_joint_type(jr, jb.type);
    if (b.joint == JointType::kFixed) {
      reject_moving_only(jr, kJointFields);
      reject_moving_only(jr, kSpringFields);
    }
    if (jb.lower > jb.upper)
      jr.fail("upper", "is below lower (" + format_key_number(jb.upper) + " < " + format_key_number(jb.lower) + ")");
    // A revolute joint's angles in radians (a limit of none is infinite: not written).
    const std::pair<const char*, double> angles[] = {{"lower", jb.lower}, {"upper", jb.upper}, {"spring_reference", b.spring_reference}};
    if (b.joint == JointType::kRevolute && jr.units_check())
      for (const auto& [key, x] : angles)
        if (std::isfinite(x) && !explain_angle_unit(x).empty()) jr.fail(key, explain_angle_unit(x));
    JointInfo info{.name = jb.name.empty() ? b.name : jb.name,
                   .lower = jb.lower, .upper = jb.upper, .effort = jb.effort, .velocity = jb.velocity,
                   .friction = jb.friction};
    if (const auto it = joint_names.find(info.name); it != joint_names.end()) {
      const std::string message = "'" + info.name + "' is already the name of the joint of bodies[" +
                                  std::to_string(it->second.index) + "] (line " + std::to_string(it->second.line) + ")";
      if (jr.has("name")) jr.fail("name", message);
      r.fail("name", message + "; this joint is named after its body (set joint.name)");
    }
    joint_names.emplace(info.name, Named{i, jr.line()});

    b.axis = jb.axis;
    b.position = jb.position;
    b.rotation = rpy_rotation(jb.rpy.x(), jb.rpy.y(), jb.rpy.z());
    b.mass = rb.mass;
    b.com = rb.com;
    b.inertia << ib.ixx, ib.ixy, ib.ixz,
                 ib.ixy, ib.iyy, ib.iyz,
                 ib.ixz, ib.iyz, ib.izz;
    // make_tree's checks, each at the line of what it concerns.
    if (b.mass > 0.0 && !r.has("inertia"))
      r.fail("inertia", "missing: a body with mass needs its inertia about the centre of mass");
    if (const std::string fault = inertia_fault(b); !fault.empty()) r.fail("inertia", fault);
    if (const std::string fault = joint_fault(b); !fault.empty()) r.fail("joint", fault);
    d.spec.bodies.push_back(std::move(b));
    d.joints.push_back(std::move(info));
  }
  // Last first, so that the earlier bodies' indices hold.
  for (auto it = flexible.rbegin(); it != flexible.rend(); ++it)
    if (const std::string fault = make_flexible(d, it->first, it->second); !fault.empty())
      bodies[static_cast<std::size_t>(it->first)].fail("flexible", fault);
  if (const std::string fault = finish_description(d); !fault.empty()) top.fail("bodies", fault);
  return d;
}

TreeDescription load_tree_yaml(const std::string& path) { return parse_tree_yaml(load_yaml_file(path), path); }

}  // namespace ff
