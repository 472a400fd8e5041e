// What a scene may not do to the rig, checked when it loads.
#include <cmath>
#include <set>

#include "sim/simulation.h"
#include "world.h"

namespace sim {
namespace {

std::string Name(const mjModel* m, int type, int id) {
  const char* n = mj_id2name(m, type, id);
  return n ? std::string("'") + n + "'" : "#" + std::to_string(id);
}

bool IsRigName(const char* name) { return name && std::string(name).rfind("tavt_", 0) == 0; }

// Axis-aligned world box of a geom (exact for boxes and the like, a bounding
// sphere for meshes and height fields).
Box3 GeomBox(const mjModel* m, const mjData* d, int g) {
  const double* s = m->geom_size + 3 * g;
  Eigen::Vector3d half;
  switch (m->geom_type[g]) {
    case mjGEOM_BOX:
    case mjGEOM_ELLIPSOID:
      half = {s[0], s[1], s[2]};
      break;
    case mjGEOM_SPHERE:
      half = {s[0], s[0], s[0]};
      break;
    case mjGEOM_CAPSULE:
      half = {s[0], s[0], s[1] + s[0]};
      break;
    case mjGEOM_CYLINDER:
      half = {s[0], s[0], s[1]};
      break;
    default: {
      const double r = m->geom_rbound[g];
      const Eigen::Vector3d c(d->geom_xpos + 3 * g);
      return {c - Eigen::Vector3d::Constant(r), c + Eigen::Vector3d::Constant(r)};
    }
  }
  Eigen::Matrix3d rot;
  for (int i = 0; i < 9; ++i) rot(i / 3, i % 3) = d->geom_xmat[9 * g + i];
  const Eigen::Vector3d extent = rot.cwiseAbs() * half;
  const Eigen::Vector3d c(d->geom_xpos + 3 * g);
  return {c - extent, c + extent};
}

bool Overlap(const Box3& a, const Box3& b) {
  return (a.min_W.array() < b.max_W.array()).all() && (b.min_W.array() < a.max_W.array()).all();
}

// A plane geom is infinite: it intrudes if any corner of the box lies behind it.
bool PlaneCutsBox(const mjModel*, const mjData* d, int g, const Box3& box) {
  const Eigen::Vector3d p(d->geom_xpos + 3 * g);
  const Eigen::Vector3d n(d->geom_xmat[9 * g + 2], d->geom_xmat[9 * g + 5],
                          d->geom_xmat[9 * g + 8]);
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner((i & 1) ? box.max_W.x() : box.min_W.x(),
                                 (i & 2) ? box.max_W.y() : box.min_W.y(),
                                 (i & 4) ? box.max_W.z() : box.min_W.z());
    if ((corner - p).dot(n) < 0) return true;
  }
  return false;
}

}  // namespace

Box3 RigWorkspace(const SimRigConfig& c) {
  // The carriages' travel plus the heads' reach (camera body about the
  // optical-centre offset), with a margin.
  const double reach = c.optical_centre_offset_m.norm() + 0.09;
  return {Eigen::Vector3d(-c.carriage_max_m - reach, -reach, -reach),
          Eigen::Vector3d(c.carriage_max_m + reach, reach, reach)};
}

void CheckSceneRules(const World& w, const Box3& keep_out) {
  const mjModel* m = w.m;
  const mjData* d = w.d;
  const std::string where = "scene '" + rig::ClipForMessage(w.scene_path) + "'";
  const int rail = mj_name2id(m, mjOBJ_BODY, "tavt_rail");
  std::set<int> rig_joints(w.joint_ids.begin(), w.joint_ids.end());
  std::set<int> rig_actuators(w.actuator_ids.begin(), w.actuator_ids.end());

  // Rule 1: nothing attached to the rig, no extra joints on it.
  for (int b = 0; b < m->nbody; ++b) {
    if (rail < 0 || m->body_rootid[b] != rail) continue;
    if (!IsRigName(mj_id2name(m, mjOBJ_BODY, b)))
      throw SceneError(where + " attaches body " + Name(m, mjOBJ_BODY, b) +
                       " to the rig (rule: scenes may not change the rig)");
  }
  for (int j = 0; j < m->njnt; ++j) {
    const bool on_rig = rail >= 0 && m->body_rootid[m->jnt_bodyid[j]] == rail;
    if (on_rig && !rig_joints.count(j))
      throw SceneError(where + " adds joint " + Name(m, mjOBJ_JOINT, j) +
                       " to the rig (rule: scenes may not change the rig)");
  }
  // Rule 2: nothing but the rig's own servos drives the rig.
  for (int u = 0; u < m->nu; ++u) {
    if (rig_actuators.count(u)) continue;
    const int type = m->actuator_trntype[u], target = m->actuator_trnid[2 * u];
    const bool hits_rig =
        ((type == mjTRN_JOINT || type == mjTRN_JOINTINPARENT) && rig_joints.count(target)) ||
        (type == mjTRN_SITE && m->body_rootid[m->site_bodyid[target]] == rail) ||
        (type == mjTRN_TENDON);
    if (hits_rig && type == mjTRN_TENDON) {
      bool uses_rig = false;
      for (int k = m->tendon_adr[target]; k < m->tendon_adr[target] + m->tendon_num[target]; ++k)
        if (m->wrap_type[k] == mjWRAP_JOINT && rig_joints.count(m->wrap_objid[k])) uses_rig = true;
      if (!uses_rig) continue;
    }
    if (hits_rig)
      throw SceneError(where + " has actuator " + Name(m, mjOBJ_ACTUATOR, u) +
                       " driving the rig (rule: scenes may not move the rig)");
  }
  for (int e = 0; e < m->neq; ++e) {
    const int type = m->eq_type[e];
    const int a = m->eq_obj1id[e], b = m->eq_obj2id[e];
    bool rig = false;
    if (type == mjEQ_JOINT) rig = rig_joints.count(a) || rig_joints.count(b);
    if (type == mjEQ_CONNECT || type == mjEQ_WELD)
      rig = (a >= 0 && m->body_rootid[a] == rail) || (b >= 0 && m->body_rootid[b] == rail);
    if (rig)
      throw SceneError(where +
                       " has an equality constraint on the rig (rule: scenes may not move "
                       "the rig)");
  }
  // Rule 3: scene geometry stays out of the rig's workspace.
  for (int g = 0; g < m->ngeom; ++g) {
    if (rail >= 0 && m->body_rootid[m->geom_bodyid[g]] == rail) continue;
    const bool intrudes = m->geom_type[g] == mjGEOM_PLANE ? PlaneCutsBox(m, d, g, keep_out)
                                                          : Overlap(GeomBox(m, d, g), keep_out);
    if (intrudes) {
      char box[160];
      std::snprintf(box, sizeof box, "x %.2f..%.2f, y %.2f..%.2f, z %.2f..%.2f m",
                    keep_out.min_W.x(), keep_out.max_W.x(), keep_out.min_W.y(), keep_out.max_W.y(),
                    keep_out.min_W.z(), keep_out.max_W.z());
      throw SceneError(where + ": geom " + Name(m, mjOBJ_GEOM, g) +
                       " reaches into the rig's workspace (" + box +
                       ") (rule: scenes may not collide with the rig)");
    }
  }
}

bool GeomTextured(const mjModel* m, int g) {
  if (g < 0 || g >= m->ngeom) return false;
  const int mat = m->geom_matid[g];
  if (mat < 0) return false;
  const int tex = m->mat_texid[mat];
  if (tex < 0) return false;
  const unsigned char* rgb = m->tex_rgb + m->tex_adr[tex];
  const long n = static_cast<long>(m->tex_width[tex]) * m->tex_height[tex];
  double sum = 0, sum2 = 0;
  for (long i = 0; i < n; ++i) {
    const double y = 0.299 * rgb[3 * i] + 0.587 * rgb[3 * i + 1] + 0.114 * rgb[3 * i + 2];
    sum += y;
    sum2 += y * y;
  }
  const double mean = sum / n;
  return std::sqrt(std::max(0.0, sum2 / n - mean * mean)) > 4.0;  // grey levels
}

}  // namespace sim
