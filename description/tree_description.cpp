#include "description/tree_description.hpp"

#include <cmath>

#include <set>
#include <stdexcept>
#include <utility>

#include "multibody/limits.hpp"

namespace ff {

Mat3 rpy_rotation(double roll, double pitch, double yaw) { return rotz(yaw) * roty(pitch) * rotx(roll); }

namespace {

// make_tree's verdict on one body alone at the base, unnamed: "" or its message without the prefix.
std::string fault_alone(BodySpec body) {
  body.name.clear();
  body.parent = -1;
  TreeSpec one;
  one.bodies.push_back(std::move(body));
  one.gravity = Vec3::Zero();
  try {
    make_tree(one);
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    const std::string prefix = "tree: body 0: ";
    return message.starts_with(prefix) ? message.substr(prefix.size()) : message;
  }
  return "";
}

}  // namespace

std::string inertia_fault(const BodySpec& body) {
  BodySpec b;
  b.joint = JointType::kFixed;
  b.mass = body.mass;
  b.com = body.com;
  b.inertia = body.inertia;
  return fault_alone(std::move(b));
}

std::string joint_fault(const BodySpec& body) {
  BodySpec b = body;
  b.mass = 0.0;
  b.com = Vec3::Zero();
  b.inertia = Mat3::Zero();
  return fault_alone(std::move(b));
}

std::string make_flexible(TreeDescription& d, int body, FlexibleLinkSpec link) {
  const int n = static_cast<int>(d.spec.bodies.size());
  if (body < 0 || body >= n) return "no body " + std::to_string(body);
  for (const FlexibleLinkInfo& f : d.flexible_links)
    if (body >= f.root_body && body <= f.tip_body) return "body \"" + f.name + "\" is already flexible";
  const BodySpec& rigid = d.spec.bodies[static_cast<std::size_t>(body)];
  link.name = rigid.name;
  link.root_name = rigid.name;
  link.root_joint = {.type = rigid.joint, .axis = rigid.axis, .armature = rigid.armature,
                     .stiffness = rigid.stiffness, .damping = rigid.damping,
                     .spring_reference = rigid.spring_reference};
  if (rigid.joint == JointType::kFixed) link.root_joint.axis = Vec3::UnitZ();

  // The bodies before `body` unchanged, then the link, then the rest with their indices shifted.
  TreeSpec spec;
  spec.gravity = d.spec.gravity;
  spec.bodies.assign(d.spec.bodies.begin(), d.spec.bodies.begin() + body);
  int tip = -1;
  try {
    tip = append_flexible_link(spec, rigid.parent, rigid.position, rigid.rotation, link);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  const int added = tip - body;  // bodies beyond the one replaced
  if (const std::string fault = tree_size_fault(static_cast<std::size_t>(n + added)); !fault.empty()) return fault;
  // The cell joints' names: per cell the joints z, y, x of flexible_link.hpp, as many as it has.
  const int per_cell = link.planar ? 1 : (link.torsion ? 3 : 2);
  std::vector<JointInfo> joints(d.joints.begin(), d.joints.begin() + body + 1);
  std::set<std::string> body_names, joint_names;
  for (int i = 0; i < n; ++i) {
    body_names.insert(d.spec.bodies[static_cast<std::size_t>(i)].name);
    joint_names.insert(d.joints.at(static_cast<std::size_t>(i)).name);
  }
  for (int k = 0; k < added; ++k) {
    const BodySpec& b = spec.bodies[static_cast<std::size_t>(body + 1 + k)];
    const char* tag = b.axis == Vec3::UnitZ() ? "z" : b.axis == Vec3::UnitY() ? "y" : "x";
    JointInfo info;
    info.name = link.name + ".cell" + std::to_string(k / per_cell + 1) + "." + tag;
    if (body_names.count(b.name)) return "its segment body \"" + b.name + "\" would take the name of another body";
    if (joint_names.count(info.name))
      return "its cell joint \"" + info.name + "\" would take the name of another joint";
    joints.push_back(std::move(info));
  }
  const double shift = link.length - flexible_link_tip_point(link).x();  // the tip segment's origin, m
  for (int i = body + 1; i < n; ++i) {
    BodySpec b = d.spec.bodies[static_cast<std::size_t>(i)];
    if (b.parent == body) {
      b.parent = tip;
      b.position.x() -= shift;
    } else if (b.parent > body) {
      b.parent += added;
    }
    spec.bodies.push_back(std::move(b));
    joints.push_back(d.joints.at(static_cast<std::size_t>(i)));
  }
  for (FlexibleLinkInfo& f : d.flexible_links)
    if (f.root_body > body) {
      f.root_body += added;
      f.tip_body += added;
    }
  FlexibleLinkInfo info{.name = link.name, .root_body = body, .tip_body = tip,
                        .tip_point = flexible_link_tip_point(link), .link = link, .dofs = {}};
  auto at = d.flexible_links.begin();
  while (at != d.flexible_links.end() && at->root_body < body) ++at;
  d.flexible_links.insert(at, std::move(info));
  d.spec = std::move(spec);
  d.joints = std::move(joints);
  return "";
}

std::vector<std::string> list_joint_names(const TreeDescription& d) {
  std::vector<std::string> out;
  for (const auto& [name, dof] : d.dof_index)
    if (name.find(".cell") == std::string::npos && name.find(".twist") == std::string::npos) out.push_back(name);
  return out;
}

std::vector<std::string> list_body_names(const TreeDescription& d) {
  std::vector<std::string> out;
  for (const auto& [name, body] : d.body_index) out.push_back(name);
  return out;
}

std::string insert_drive_train(TreeDescription& d, const std::string& joint, const DriveTrain& drive) {
  const auto dof = d.dof_index.find(joint);
  if (dof == d.dof_index.end()) return "no moving joint named '" + joint + "'";
  if (!(drive.rotor_inertia >= 0.0) || !(drive.ratio > 0.0) || !(drive.stiffness > 0.0) || !(drive.damping >= 0.0) ||
      !std::isfinite(drive.rotor_inertia + drive.ratio + drive.stiffness + drive.damping))
    return "a drive needs rotor_inertia >= 0, ratio > 0, stiffness > 0 and damping >= 0, all finite";
  if (!(drive.cubic_stiffness >= 0.0) || !(drive.backlash >= 0.0) || !(drive.efficiency > 0.0 && drive.efficiency <= 1.0) ||
      !std::isfinite(drive.cubic_stiffness + drive.backlash))
    return "a drive needs cubic_stiffness >= 0, backlash >= 0 and efficiency in (0, 1], all finite";
  int body = -1;
  for (std::size_t i = 0; i < d.joints.size(); ++i)
    if (d.joints[i].name == joint) body = static_cast<int>(i);
  const BodySpec link = d.spec.bodies[static_cast<std::size_t>(body)];
  const std::string rotor_name = link.name + ".rotor", twist_name = joint + ".twist";
  if (d.body_index.count(rotor_name) || d.dof_index.count(twist_name))
    return "the drive's names '" + rotor_name + "' and '" + twist_name + "' must be free";
  TreeDescription out = d;
  // The rotor: the joint as it was, massless, with the rotor's reflected inertia on its axis.
  BodySpec rotor = link;
  rotor.name = rotor_name;
  rotor.mass = 0.0;
  rotor.com = Vec3::Zero();
  rotor.inertia = Mat3::Zero();
  rotor.armature = link.armature + drive.ratio * drive.ratio * drive.rotor_inertia;
  // The link: turned by the twist about the same axis, from the rotor's frame.
  BodySpec twisted = link;
  twisted.parent = body;
  twisted.position = Vec3::Zero();
  twisted.rotation = Mat3::Identity();
  twisted.armature = 0.0;
  twisted.stiffness = drive.stiffness;
  twisted.damping = drive.damping;
  twisted.spring_reference = 0.0;
  JointInfo twist_info;
  twist_info.name = twist_name;
  out.spec.bodies[static_cast<std::size_t>(body)] = twisted;
  out.spec.bodies.insert(out.spec.bodies.begin() + body, rotor);
  out.joints.insert(out.joints.begin() + body + 1, twist_info);
  for (std::size_t i = static_cast<std::size_t>(body) + 2; i < out.spec.bodies.size(); ++i)
    if (out.spec.bodies[i].parent >= body) ++out.spec.bodies[i].parent;
  for (FlexibleLinkInfo& f : out.flexible_links) {
    if (f.root_body >= body) ++f.root_body;
    if (f.tip_body >= body) ++f.tip_body;
  }
  if (const std::string fault = finish_description(out); !fault.empty()) return fault;
  d = std::move(out);
  return "";
}

std::string finish_description(TreeDescription& d) {
  d.body_index.clear();
  d.dof_index.clear();
  std::vector<int> dofs(d.spec.bodies.size(), -1);
  int dof = 0;
  for (std::size_t i = 0; i < d.spec.bodies.size(); ++i) {
    d.body_index[d.spec.bodies[i].name] = static_cast<int>(i);
    if (d.spec.bodies[i].joint != JointType::kFixed) {
      dofs[i] = dof;
      d.dof_index[d.joints.at(i).name] = dof++;
    }
  }
  for (FlexibleLinkInfo& f : d.flexible_links) {
    f.dofs.clear();
    for (int i = f.root_body + 1; i <= f.tip_body; ++i)
      if (dofs[static_cast<std::size_t>(i)] >= 0) f.dofs.push_back(dofs[static_cast<std::size_t>(i)]);
  }
  try {
    make_tree(d.spec);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace ff
