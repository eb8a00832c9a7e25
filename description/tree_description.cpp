#include "description/tree_description.hpp"

#include <stdexcept>
#include <utility>

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

std::string finish_description(TreeDescription& d) {
  d.body_index.clear();
  d.dof_index.clear();
  int dof = 0;
  for (std::size_t i = 0; i < d.spec.bodies.size(); ++i) {
    d.body_index[d.spec.bodies[i].name] = static_cast<int>(i);
    if (d.spec.bodies[i].joint != JointType::kFixed) d.dof_index[d.joints.at(i).name] = dof++;
  }
  try {
    make_tree(d.spec);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace ff
