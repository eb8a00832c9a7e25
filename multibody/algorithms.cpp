// Kinematic-tree dynamics (algorithms.hpp): RNEA, CRBA, ABA and energies in spatial vectors,
// Featherstone, Rigid Body Dynamics Algorithms, 2008, Tables 5.1, 6.2, 7.1.
#include "multibody/algorithms.hpp"

#include <stdexcept>
#include <string>

namespace ff {

namespace {

using ConstVec = Eigen::Ref<const Eigen::VectorXd>;

void check_size(const char* fn, const char* name, Eigen::Index got, int want) {
  if (got != want)
    throw std::invalid_argument(std::string(fn) + ": " + name + " has " + std::to_string(got) +
                                " entries, the tree has " + std::to_string(want));
}

void check_workspace(const char* fn, const Tree& tree, const TreeWorkspace& ws) {
  if (static_cast<int>(ws.Xup.size()) != tree.num_bodies())
    throw std::invalid_argument(std::string(fn) + ": the workspace was not made for this tree (" +
                                std::to_string(ws.Xup.size()) + " bodies, the tree has " +
                                std::to_string(tree.num_bodies()) + ")");
}

// The joint coordinate of body b (0 for a fixed joint, whose transform ignores it).
double coord(const Body& b, const ConstVec& x) { return b.dof >= 0 ? x[b.dof] : 0.0; }

// ws.Xup[i] = X_J(q_i) X_tree,i for every body.
void calc_parent_transforms(const Tree& tree, const ConstVec& q, TreeWorkspace& ws) {
  for (int i = 0; i < tree.num_bodies(); ++i) {
    const Body& b = tree.body(i);
    ws.Xup[i] = joint_transform(b, coord(b, q)) * b.X_tree;
  }
}

// ws.X0[i] = i X_0 from ws.Xup.
void calc_base_transforms(const Tree& tree, TreeWorkspace& ws) {
  for (int i = 0; i < tree.num_bodies(); ++i) {
    const int p = tree.body(i).parent;
    ws.X0[i] = p < 0 ? ws.Xup[i] : ws.Xup[i] * ws.X0[p];
  }
}

// RNEA (RBDA Table 5.1) with qdd = 0 when `qdd` is null.
//   forward:  v_i = X_i v_p + S_i qd_i,  a_i = X_i a_p + S_i qdd_i + v_i × S_i qd_i   (a_0 = -a_g)
//             f_i = I_i a_i + v_i ×* I_i v_i
//   backward: tau_i = S_i^T f_i + armature_i qdd_i,  f_p += X_i^T f_i
void rnea(const Tree& tree, const ConstVec& q, const ConstVec& qd, const ConstVec* qdd, Eigen::Ref<Eigen::VectorXd> tau,
          TreeWorkspace& ws) {
  calc_parent_transforms(tree, q, ws);
  const SpatialMotion a0 = tree.base_acceleration();
  const int n = tree.num_bodies();
  for (int i = 0; i < n; ++i) {
    const Body& b = tree.body(i);
    const SpatialMotion vJ = b.S * coord(b, qd);
    const double qddi = qdd ? coord(b, *qdd) : 0.0;
    if (b.parent < 0) {
      ws.v[i] = vJ;  // the base is still: v_i × vJ = vJ × vJ = 0
      ws.a[i] = ws.Xup[i].apply(a0) + b.S * qddi;
    } else {
      ws.v[i] = ws.Xup[i].apply(ws.v[b.parent]) + vJ;
      ws.a[i] = ws.Xup[i].apply(ws.a[b.parent]) + b.S * qddi + cross_motion(ws.v[i], vJ);
    }
    ws.f[i] = b.inertia * ws.a[i] + cross_force(ws.v[i], b.inertia * ws.v[i]);
  }
  for (int i = n - 1; i >= 0; --i) {
    const Body& b = tree.body(i);
    if (b.dof >= 0) tau[b.dof] = b.S.dot(ws.f[i]) + (qdd ? b.armature * (*qdd)[b.dof] : 0.0);
    if (b.parent >= 0) ws.f[b.parent] += ws.Xup[i].apply_inverse_force(ws.f[i]);
  }
}

}  // namespace

TreeWorkspace::TreeWorkspace(const Tree& tree) {
  const auto n = static_cast<std::size_t>(tree.num_bodies());
  Xup.resize(n);
  X0.resize(n);
  v.assign(n, SpatialMotion::Zero());
  a.assign(n, SpatialMotion::Zero());
  c.assign(n, SpatialMotion::Zero());
  f.assign(n, SpatialForce::Zero());
  I.assign(n, SpatialMatrix::Zero());
  U.assign(n, SpatialForce::Zero());
  d.assign(n, 0.0);
  u.assign(n, 0.0);
}

Transform joint_transform(const Body& body, double q) {
  switch (body.joint) {
    case JointType::kRevolute:
      return Transform::rotation(axis_angle(body.axis, q).transpose());
    case JointType::kPrismatic:
      return Transform::translation(body.axis * q);
    case JointType::kFixed:
      break;
  }
  return Transform{};
}

void calc_inverse_dynamics(const Tree& tree, const ConstVec& q, const ConstVec& qd, const ConstVec& qdd,
                           Eigen::Ref<Eigen::VectorXd> tau, TreeWorkspace& ws) {
  const char* fn = "calc_inverse_dynamics";
  check_workspace(fn, tree, ws);
  check_size(fn, "q", q.size(), tree.nq());
  check_size(fn, "qd", qd.size(), tree.nv());
  check_size(fn, "qdd", qdd.size(), tree.nv());
  check_size(fn, "tau", tau.size(), tree.nv());
  rnea(tree, q, qd, &qdd, tau, ws);
}

void calc_bias_forces(const Tree& tree, const ConstVec& q, const ConstVec& qd, Eigen::Ref<Eigen::VectorXd> bias,
                      TreeWorkspace& ws) {
  const char* fn = "calc_bias_forces";
  check_workspace(fn, tree, ws);
  check_size(fn, "q", q.size(), tree.nq());
  check_size(fn, "qd", qd.size(), tree.nv());
  check_size(fn, "bias", bias.size(), tree.nv());
  rnea(tree, q, qd, nullptr, bias, ws);
}

// CRBA (RBDA Table 6.2):
//   I^c_i = I_i;  for i = N..1: I^c_p += X_i^T I^c_i X_i
//   for each joint i: F = I^c_i S_i, H_ii = S_i^T F + armature_i;
//     up the chain j = i, p(i), ...: F = X_j^T F, j = p(j), H_ij = H_ji = F^T S_j.
void calc_mass_matrix(const Tree& tree, const ConstVec& q, Eigen::Ref<Eigen::MatrixXd> M, TreeWorkspace& ws) {
  const char* fn = "calc_mass_matrix";
  check_workspace(fn, tree, ws);
  check_size(fn, "q", q.size(), tree.nq());
  if (M.rows() != tree.nv() || M.cols() != tree.nv())
    throw std::invalid_argument(std::string(fn) + ": M is " + std::to_string(M.rows()) + " x " +
                                std::to_string(M.cols()) + ", the tree has nv = " + std::to_string(tree.nv()));
  calc_parent_transforms(tree, q, ws);
  const int n = tree.num_bodies();
  for (int i = 0; i < n; ++i) ws.I[i] = tree.body(i).inertia;
  for (int i = n - 1; i >= 0; --i) {
    const int p = tree.body(i).parent;
    if (p >= 0) ws.I[p] += transform_inertia_to_parent(ws.Xup[i], ws.I[i]);
  }
  M.setZero();
  for (int i = 0; i < n; ++i) {
    const Body& b = tree.body(i);
    if (b.dof < 0) continue;
    SpatialForce F = ws.I[i] * b.S;
    M(b.dof, b.dof) = b.S.dot(F) + b.armature;
    for (int j = i; tree.body(j).parent >= 0;) {
      F = ws.Xup[j].apply_inverse_force(F);
      j = tree.body(j).parent;
      const Body& bj = tree.body(j);
      if (bj.dof >= 0) M(b.dof, bj.dof) = M(bj.dof, b.dof) = F.dot(bj.S);
    }
  }
}

// ABA (RBDA Table 7.1), armature as a joint-space term in D_i:
//   pass 1: v_i = X_i v_p + S_i qd_i, c_i = v_i × S_i qd_i, I^A_i = I_i, p^A_i = v_i ×* I_i v_i
//   pass 2 (i = N..1): U_i = I^A_i S_i, D_i = S_i^T U_i + armature_i, u_i = tau_i - S_i^T p^A_i;
//           I^a = I^A_i - U_i U_i^T / D_i, p^a = p^A_i + I^a c_i + U_i u_i / D_i,
//           I^A_p += X_i^T I^a X_i, p^A_p += X_i^T p^a
//   pass 3: a' = X_i a_p + c_i (a_0 = -a_g), qdd_i = (u_i - U_i^T a') / D_i, a_i = a' + S_i qdd_i
// A fixed joint passes I^A_i and p^A_i (its c_i = 0) to the parent unchanged.
void calc_forward_dynamics(const Tree& tree, const ConstVec& q, const ConstVec& qd, const ConstVec& tau,
                           Eigen::Ref<Eigen::VectorXd> qdd, TreeWorkspace& ws) {
  const char* fn = "calc_forward_dynamics";
  check_workspace(fn, tree, ws);
  check_size(fn, "q", q.size(), tree.nq());
  check_size(fn, "qd", qd.size(), tree.nv());
  check_size(fn, "tau", tau.size(), tree.nv());
  check_size(fn, "qdd", qdd.size(), tree.nv());
  calc_parent_transforms(tree, q, ws);
  const int n = tree.num_bodies();
  for (int i = 0; i < n; ++i) {
    const Body& b = tree.body(i);
    const SpatialMotion vJ = b.S * coord(b, qd);
    if (b.parent < 0) {
      ws.v[i] = vJ;
      ws.c[i].setZero();
    } else {
      ws.v[i] = ws.Xup[i].apply(ws.v[b.parent]) + vJ;
      ws.c[i] = cross_motion(ws.v[i], vJ);
    }
    ws.I[i] = b.inertia;
    ws.f[i] = cross_force(ws.v[i], b.inertia * ws.v[i]);
  }
  for (int i = n - 1; i >= 0; --i) {
    const Body& b = tree.body(i);
    if (b.dof >= 0) {
      ws.U[i] = ws.I[i] * b.S;
      ws.d[i] = b.S.dot(ws.U[i]) + b.armature;
      ws.u[i] = tau[b.dof] - b.S.dot(ws.f[i]);
    }
    if (b.parent < 0) continue;
    SpatialMatrix Ia = ws.I[i];
    SpatialForce pa = ws.f[i];
    if (b.dof >= 0) {
      Ia.noalias() -= (ws.U[i] / ws.d[i]) * ws.U[i].transpose();
      pa += Ia * ws.c[i] + ws.U[i] * (ws.u[i] / ws.d[i]);
    }
    ws.I[b.parent] += transform_inertia_to_parent(ws.Xup[i], Ia);
    ws.f[b.parent] += ws.Xup[i].apply_inverse_force(pa);
  }
  const SpatialMotion a0 = tree.base_acceleration();
  for (int i = 0; i < n; ++i) {
    const Body& b = tree.body(i);
    SpatialMotion a = ws.Xup[i].apply(b.parent < 0 ? a0 : ws.a[b.parent]) + ws.c[i];
    if (b.dof >= 0) {
      const double qddi = (ws.u[i] - ws.U[i].dot(a)) / ws.d[i];
      qdd[b.dof] = qddi;
      a += b.S * qddi;
    }
    ws.a[i] = a;
  }
}

// T = sum 1/2 v_i . I_i v_i (body coordinates) + sum 1/2 armature qd².
double calc_kinetic_energy(const Tree& tree, const ConstVec& q, const ConstVec& qd, TreeWorkspace& ws) {
  const char* fn = "calc_kinetic_energy";
  check_workspace(fn, tree, ws);
  check_size(fn, "q", q.size(), tree.nq());
  check_size(fn, "qd", qd.size(), tree.nv());
  calc_parent_transforms(tree, q, ws);
  double T = 0.0;
  for (int i = 0; i < tree.num_bodies(); ++i) {
    const Body& b = tree.body(i);
    const SpatialMotion vJ = b.S * coord(b, qd);
    ws.v[i] = b.parent < 0 ? vJ : SpatialMotion(ws.Xup[i].apply(ws.v[b.parent]) + vJ);
    T += 0.5 * ws.v[i].dot(b.inertia * ws.v[i]);
    if (b.dof >= 0) T += 0.5 * b.armature * qd[b.dof] * qd[b.dof];
  }
  return T;
}

// V = -sum m_i g . c_i with c_i = the centre of mass in base coordinates.
double calc_potential_energy(const Tree& tree, const ConstVec& q, TreeWorkspace& ws) {
  const char* fn = "calc_potential_energy";
  check_workspace(fn, tree, ws);
  check_size(fn, "q", q.size(), tree.nq());
  calc_parent_transforms(tree, q, ws);
  calc_base_transforms(tree, ws);
  double V = 0.0;
  for (int i = 0; i < tree.num_bodies(); ++i) {
    const Body& b = tree.body(i);
    V -= b.mass * tree.gravity().dot(ws.X0[i].apply_inverse_point(b.com));
  }
  return V;
}

void calc_passive_forces(const Tree& tree, const ConstVec& q, const ConstVec& qd, Eigen::Ref<Eigen::VectorXd> tau) {
  const char* fn = "calc_passive_forces";
  check_size(fn, "q", q.size(), tree.nq());
  check_size(fn, "qd", qd.size(), tree.nv());
  check_size(fn, "tau", tau.size(), tree.nv());
  for (const Body& b : tree.bodies())
    if (b.dof >= 0) tau[b.dof] = -b.stiffness * (q[b.dof] - b.spring_reference) - b.damping * qd[b.dof];
}

double calc_spring_energy(const Tree& tree, const ConstVec& q) {
  check_size("calc_spring_energy", "q", q.size(), tree.nq());
  double V = 0.0;
  for (const Body& b : tree.bodies()) {
    if (b.dof < 0) continue;
    const double dq = q[b.dof] - b.spring_reference;
    V += 0.5 * b.stiffness * dq * dq;
  }
  return V;
}

namespace {

// Checks a point-load call and fills ws.X0 (base to body) for q.
void prepare_point(const char* fn, const Tree& tree, const ConstVec& q, int body, TreeWorkspace& ws) {
  check_workspace(fn, tree, ws);
  check_size(fn, "q", q.size(), tree.nq());
  if (body < 0 || body >= tree.num_bodies())
    throw std::invalid_argument(std::string(fn) + ": no body " + std::to_string(body) + " (the tree has " +
                                std::to_string(tree.num_bodies()) + ")");
  calc_parent_transforms(tree, q, ws);
  calc_base_transforms(tree, ws);
}

// Column of joint j (body bj) for the point p (base coordinates): [a; a × (p - o)] or [0; a].
SpatialMotion point_column(const Body& bj, const Transform& X0j, const Vec3& p) {
  const Vec3 a = X0j.E.transpose() * bj.axis;  // the axis is the same in the joint and the body frame
  SpatialMotion col = SpatialMotion::Zero();
  if (bj.joint == JointType::kRevolute) {
    col.head<3>() = a;
    col.tail<3>() = a.cross(p - X0j.r);
  } else {
    col.tail<3>() = a;
  }
  return col;
}

}  // namespace

void calc_point_jacobian(const Tree& tree, const ConstVec& q, int body, const Vec3& point,
                         Eigen::Ref<Eigen::MatrixXd> J, TreeWorkspace& ws) {
  const char* fn = "calc_point_jacobian";
  if (J.rows() != 6 || J.cols() != tree.nv())
    throw std::invalid_argument(std::string(fn) + ": J is " + std::to_string(J.rows()) + " x " +
                                std::to_string(J.cols()) + ", it must be 6 x nv = 6 x " + std::to_string(tree.nv()));
  prepare_point(fn, tree, q, body, ws);
  J.setZero();
  const Vec3 p = ws.X0[body].apply_inverse_point(point);
  for (int j = body; j >= 0; j = tree.body(j).parent) {
    const Body& bj = tree.body(j);
    if (bj.dof >= 0) J.col(bj.dof) = point_column(bj, ws.X0[j], p);
  }
}

void add_point_load(const Tree& tree, const ConstVec& q, int body, const Vec3& point, const Vec3& force,
                    const Vec3& moment, Eigen::Ref<Eigen::VectorXd> tau, TreeWorkspace& ws) {
  const char* fn = "add_point_load";
  check_size(fn, "tau", tau.size(), tree.nv());
  prepare_point(fn, tree, q, body, ws);
  SpatialForce w;
  w << moment, force;
  const Vec3 p = ws.X0[body].apply_inverse_point(point);
  for (int j = body; j >= 0; j = tree.body(j).parent) {
    const Body& bj = tree.body(j);
    if (bj.dof >= 0) tau[bj.dof] += point_column(bj, ws.X0[j], p).dot(w);
  }
}

void calc_body_poses(const Tree& tree, const ConstVec& q, std::span<Pose> poses) {
  check_size("calc_body_poses", "q", q.size(), tree.nq());
  check_size("calc_body_poses", "poses", static_cast<Eigen::Index>(poses.size()), tree.num_bodies());
  // Pose of i from its parent's: R_i = R_p E_tree^T R_J, p_i = p_p + R_p r_i (r_i = i's origin in p's frame).
  for (int i = 0; i < tree.num_bodies(); ++i) {
    const Body& b = tree.body(i);
    const Transform X = joint_transform(b, coord(b, q)) * b.X_tree;  // i X_p
    if (b.parent < 0) {
      poses[i] = Pose{X.rotation_matrix(), X.position()};
    } else {
      const Pose& pp = poses[b.parent];
      poses[i] = Pose{pp.rotation * X.rotation_matrix(), pp.position + pp.rotation * X.position()};
    }
  }
}

Pose calc_body_pose(const Tree& tree, const ConstVec& q, int body) {
  check_size("calc_body_pose", "q", q.size(), tree.nq());
  if (body < 0 || body >= tree.num_bodies())
    throw std::invalid_argument("calc_body_pose: no body " + std::to_string(body) + " (the tree has " +
                                std::to_string(tree.num_bodies()) + ")");
  // i X_0 = i X_p p X_pp ... composed up the chain.
  Transform X;
  for (int j = body; j >= 0; j = tree.body(j).parent) {
    const Body& b = tree.body(j);
    X = X * (joint_transform(b, coord(b, q)) * b.X_tree);
  }
  return Pose{X.rotation_matrix(), X.position()};
}

Vec3 calc_point_position(const Tree& tree, const ConstVec& q, int body, const Vec3& point) {
  return calc_body_pose(tree, q, body).point(point);
}

}  // namespace ff
