#include "solver/joint_solver.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>

#include "core/parallel.h"
#include "islands/islands.h"

namespace rubble::detail {
namespace {

constexpr std::size_t kJointChunk = 1024;
constexpr float kPi = 3.14159265358979f;
/// The large islands' joints run serially in store order below this many (a chain of a few hundred links keeps the
/// order that carries its load down in one pass), in colours across the threads from it on, where one colour holds
/// thousands of joints and a wait between colours costs a few microseconds.
constexpr std::uint32_t kColouredJoints = 1024;
/// Work per task within one colour, a few microseconds of it: batches of ball joints, or other joints.
constexpr std::size_t kBatchChunk = 32;
constexpr std::size_t kColourChunk = 128;
/// The large islands' joints split into two slabs only when at most 1 / kMaxCrossingShare of them cross the cut.
constexpr std::uint32_t kMaxCrossingShare = 8;
/// Colours beyond this go to one overflow set solved serially after the others (bodies with over 63 joints).
constexpr std::uint32_t kMaxJointColours = 63;
constexpr std::uint32_t kJointOverflowColour = kMaxJointColours;

struct Velocity {
    Vec3 v, w;
};

Velocity loadRow(const SolverBodies& b, std::int32_t row) {
    if (row < 0) return {};
    const BodyRow& r = b.velocity[static_cast<std::size_t>(row)];
    return {r.linear, r.angular};
}

void storeRow(SolverBodies& b, std::int32_t row, const Velocity& s) {
    b.velocity[static_cast<std::size_t>(row)] = {s.v, s.w};
}

/// The two bodies of a joint during one solve: velocities in, impulses applied, velocities out (dynamic sides only).
struct Bodies {
    const JointRow& r;
    Velocity a, b;

    Bodies(const JointRow& row, const SolverBodies& rows)
        : r(row), a(loadRow(rows, row.rowA)), b(loadRow(rows, row.rowB)) {}

    Vec3 pointVelocity() const { return (b.v + cross(b.w, r.rB)) - (a.v + cross(a.w, r.rA)); }
    Vec3 angularVelocity() const { return b.w - a.w; }

    /// Impulse p on B at its anchor, -p on A at its anchor.
    void applyLinear(Vec3 p) {
        a.v -= p * r.invMassA;
        a.w -= r.inertiaA * cross(r.rA, p);
        b.v += p * r.invMassB;
        b.w += r.inertiaB * cross(r.rB, p);
    }
    /// Angular impulse l on B, -l on A.
    void applyAngular(Vec3 l) {
        a.w -= r.inertiaA * l;
        b.w += r.inertiaB * l;
    }
    void store(SolverBodies& rows) const {
        if (r.dynamicA) storeRow(rows, r.rowA, a);
        if (r.dynamicB) storeRow(rows, r.rowB, b);
    }
};

JointSym3 inverse(const JointSym3& m) {
    const float c00 = m.yy * m.zz - m.yz * m.yz;
    const float c01 = m.xz * m.yz - m.xy * m.zz;
    const float c02 = m.xy * m.yz - m.xz * m.yy;
    const float det = m.xx * c00 + m.xy * c01 + m.xz * c02;
    if (!(det > 0)) return {};
    const float inv = 1.0f / det;
    return {c00 * inv, (m.xx * m.zz - m.xz * m.xz) * inv, (m.xx * m.yy - m.xy * m.xy) * inv, c01 * inv,
            c02 * inv, (m.xy * m.xz - m.xx * m.yz) * inv};
}

/// K = m I - [r]x I^-1 [r]x: how an impulse at the anchor changes the anchor's velocity.
void addPointMass(JointSym3& k, float invMass, const JointSym3& inertia, Vec3 r) {
    const Vec3 cx = cross(inertia * cross(r, {1, 0, 0}), r);
    const Vec3 cy = cross(inertia * cross(r, {0, 1, 0}), r);
    const Vec3 cz = cross(inertia * cross(r, {0, 0, 1}), r);
    k.xx += invMass + cx.x, k.yy += invMass + cy.y, k.zz += invMass + cz.z;
    k.xy += cy.x, k.xz += cz.x, k.yz += cz.y;
}

float angularMass(const JointSym3& inertia, Vec3 a, Vec3 b) { return dot(a, inertia * b); }

void perpendiculars(Vec3 a, Vec3& t1, Vec3& t2) {
    const Vec3 helper = std::fabs(a.x) < 0.57f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
    t1 = cross(a, helper);
    t1 = t1 * (1.0f / length(t1));
    t2 = cross(a, t1);
}

JointSym3 sum(const JointSym3& a, const JointSym3& b) {
    return {a.xx + b.xx, a.yy + b.yy, a.zz + b.zz, a.xy + b.xy, a.xz + b.xz, a.yz + b.yz};
}

struct Softness {
    float biasRate = 0, massScale = 1, impulseScale = 0;
};

/// A spring-damper of natural frequency `hertz` and damping ratio `zeta` relative to the row's own effective mass,
/// solved implicitly over the substep h.
Softness soft(float hertz, float zeta, float h) {
    const float omega = 2.0f * kPi * hertz;
    const float a1 = 2.0f * zeta + h * omega;
    const float a2 = h * omega * a1;
    const float a3 = 1.0f / (1.0f + a2);
    return {omega / a1, a2 * a3, a3};
}

/// Hooke's spring k with damping c on a row of effective mass 1 / K: gamma = 1 / (h (c + h k)) is the compliance
/// in impulse units, k / (c + h k) = beta / h the bias rate.
Softness spring(float k, float c, float K, float h) {
    const float gamma = 1.0f / (h * (c + h * k));
    return {k / (c + h * k), K / (K + gamma), gamma / (K + gamma)};
}

/// Hinge angle of B about A's axis (local to A) from conj(qA) qB conj(reference), in (-pi, pi].
float hingeAngleOf(Quat qA, Quat qB, Quat reference, Vec3 localAxisA) {
    const Quat rel = conjugate(qA) * qB * conjugate(reference);
    float angle = 2.0f * std::atan2(dot(Vec3{rel.x, rel.y, rel.z}, localAxisA), rel.w);
    if (angle > kPi) angle -= 2.0f * kPi;
    if (angle <= -kPi) angle += 2.0f * kPi;
    return angle;
}

struct Side {
    Vec3 com;
    Quat q;
    Vec3 r;  ///< anchor from the centre of mass, world
    std::int32_t row = -1;
    bool dynamic = false;
    float invMass = 0;
    JointSym3 inertia;
};

/// `coupled`: the body's dense index when moving (JointCoupling::bodies), else kNoCoupledBody.
Side sideOf(const BodyStorage& storage, const ContactSolver& contacts, BodyId id, std::uint32_t coupled,
            Vec3 localAnchor) {
    Side s;
    const bool moving = coupled != kNoCoupledBody;
    const std::uint32_t d = moving ? coupled : storage.find(id)->dense;
    if (!moving) {
        const StaticBodies& b = storage.statics;
        s.com = {b.px[d], b.py[d], b.pz[d]};
        s.q = {b.qx[d], b.qy[d], b.qz[d], b.qw[d]};
        s.r = rotate(s.q, localAnchor);
        return s;
    }
    const MovingBodies& m = storage.moving;
    s.com = {m.px[d], m.py[d], m.pz[d]};
    s.q = {m.qx[d], m.qy[d], m.qz[d], m.qw[d]};
    s.r = rotate(s.q, localAnchor - Vec3{m.lcx[d], m.lcy[d], m.lcz[d]});
    s.row = contacts.solverIndexOf(d);
    // The contact solver's masses: zero for the bodies it holds still (kinematic, frozen, asleep), no inertia
    // without Effect::Rotation.
    if (s.row < 0) return s;
    const MassRow& mass = contacts.bodies().mass[static_cast<std::size_t>(s.row)];
    s.dynamic = mass.inverseMass > 0;
    s.invMass = mass.inverseMass;
    const float* i = mass.inverseInertia;
    s.inertia = {i[0], i[1], i[2], i[3], i[4], i[5]};
    return s;
}

/// Inverse of the point rows' effective mass at the row's anchors: how an impulse there changes their relative
/// velocity.
JointSym3 pointMassOf(const JointRow& r) {
    JointSym3 k;
    addPointMass(k, r.invMassA, r.inertiaA, r.rA);
    addPointMass(k, r.invMassB, r.inertiaB, r.rB);
    return inverse(k);
}

/// How an impulse along the row's axis at its anchors changes their relative speed along it.
float axialK(const JointRow& r) {
    const Vec3 ra = cross(r.rA, r.axis), rb = cross(r.rB, r.axis);
    return r.invMassA + r.invMassB + dot(ra, r.inertiaA * ra) + dot(rb, r.inertiaB * rb);
}

}  // namespace

float hingeAngle(const Joint& joint, const BodyStorage& storage) {
    const auto orientation = [&](BodyId id) {
        const BodySlot& slot = *storage.find(id);
        const std::uint32_t d = slot.dense;
        if (slot.set == BodySet::Static)
            return Quat{storage.statics.qx[d], storage.statics.qy[d], storage.statics.qz[d], storage.statics.qw[d]};
        return Quat{storage.moving.qx[d], storage.moving.qy[d], storage.moving.qz[d], storage.moving.qw[d]};
    };
    return hingeAngleOf(orientation(joint.bodyA), orientation(joint.bodyB), joint.referenceRotation, joint.localAxisA);
}

void JointSolver::couple(const JointStore& store, const BodyStorage& storage, JointCoupling& out,
                         TaskPool& pool) const {
    // Two entries per joint, in the store's order, filled in parallel. The pairs change only with the joints: listed
    // and sorted again only then.
    const std::vector<Joint>& joints = store.joints();
    const bool listPairs = out.pairsVersion != store.pairsVersion();
    out.bodies.resize(2 * joints.size());
    if (listPairs) out.noContactPairs.resize(joints.size());
    constexpr std::uint64_t kNoPair = ~std::uint64_t{0};
    pool.forChunks(joints.size(), kJointChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            const Joint& j = joints[i];
            const BodySlot& a = *storage.find(j.bodyA);
            const BodySlot& b = *storage.find(j.bodyB);
            out.bodies[2 * i] = !j.broken && a.set == BodySet::Moving ? a.dense : kNoCoupledBody;
            out.bodies[2 * i + 1] = !j.broken && b.set == BodySet::Moving ? b.dense : kNoCoupledBody;
            if (listPairs)
                out.noContactPairs[i] =
                    j.broken || j.collideConnected ? kNoPair : jointedPairKey(j.bodyA.index, j.bodyB.index);
        }
    });
    if (!listPairs) return;
    std::sort(out.noContactPairs.begin(), out.noContactPairs.end());
    out.noContactPairs.erase(std::unique(out.noContactPairs.begin(), out.noContactPairs.end()),
                             out.noContactPairs.end());
    if (!out.noContactPairs.empty() && out.noContactPairs.back() == kNoPair) out.noContactPairs.pop_back();
    out.pairsVersion = store.pairsVersion();
}

void JointSolver::prepare(const JointStore& store, const BodyStorage& storage, const ContactSolver& contacts,
                          const JointCoupling& coupling, const WorldSettings& settings, float h, TaskPool& pool,
                          const Islands* islands) {
    h_ = h;
    const SolverSettings& solver = settings.solver;
    const Softness rigid = solver.positionCorrection == PositionCorrection::SoftStep
                               ? soft(std::min(solver.jointHertz, 0.25f / h), solver.jointDampingRatio, h)
                               : Softness{solver.baumgarte / h, 1.0f, 0.0f};
    rigid_ = {rigid.biasRate, rigid.massScale, rigid.impulseScale};
    const std::vector<Joint>& joints = store.joints();
    rows_.resize(joints.size());
    frames_.resize(joints.size());
    links_.resize(joints.size());
    // Each joint's body rows and segment first (all that partitioning and colouring read); then the rows themselves,
    // the batched ball joints' straight into their lanes. A joint's island is its dynamic body's (both bodies of a
    // joint between dynamic bodies share one); joints of islands outside any block, and without islands every
    // joint, go with the large islands.
    const std::uint32_t segments = static_cast<std::uint32_t>(contacts.blocks().size()) + 1;
    const SolverBodies& bodyRows = contacts.bodies();
    pool.forChunks(joints.size(), kJointChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            const Joint& j = joints[i];
            JointLink& l = links_[i];
            l = JointLink{};
            if (j.broken) continue;
            const auto rowOf = [&](std::uint32_t dense, bool& dynamic) {
                const std::int32_t row = dense == kNoCoupledBody ? -1 : contacts.solverIndexOf(dense);
                dynamic = row >= 0 && bodyRows.mass[static_cast<std::size_t>(row)].inverseMass > 0;
                return row;
            };
            l.rowA = rowOf(coupling.bodies[2 * i], l.dynamicA);
            l.rowB = rowOf(coupling.bodies[2 * i + 1], l.dynamicB);
            if (!l.dynamicA && !l.dynamicB) continue;
            l.ball = j.type == JointType::Ball;
            l.segment = segments - 1;
            if (islands == nullptr) continue;
            const std::uint32_t dense = bodyRows.moving[static_cast<std::size_t>(l.dynamicA ? l.rowA : l.rowB)];
            const std::uint32_t island = dense < islands->islandOf.size() ? islands->islandOf[dense] : kNoIsland;
            if (island != kNoIsland) l.segment = std::min(contacts.segmentOfIsland(island), segments - 1);
        }
    });
    // The segments and colours follow from the links alone: a joint graph that did not change (the usual step) keeps
    // last step's.
    const auto sameLinks = [&] {
        if (segments != linkedSegments_ || links_.size() != lastLinks_.size()) return false;
        for (std::size_t i = 0; i < links_.size(); ++i)
            if (!links_[i].sameBodies(lastLinks_[i])) return false;
        return true;
    };
    if (sameLinks()) {
        links_ = lastLinks_;  // with their batched flags
    } else {
        partition(contacts, storage.moving, segments);
        lastLinks_ = links_;
        linkedSegments_ = segments;
    }
    const BuildInputs in{store, storage, contacts, coupling, rigid_, h, solver.warmStarting};
    pool.forChunks(joints.size(), kJointChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i)
            if (!links_[i].batched) buildRow(static_cast<std::uint32_t>(i), in);
    });
    const auto stillRow = static_cast<std::int32_t>(bodyRows.count);
    pool.forChunks(batches_.size(), kBatchChunk, [&](std::size_t, std::size_t from, std::size_t to, int) {
        for (std::size_t k = from; k < to; ++k)
            buildBatch(batches_[k], batchJoints_[k].first, batchJoints_[k].count, stillRow, in);
    });
}

void JointSolver::buildRow(std::uint32_t i, const BuildInputs& in) {
    const Joint& j = in.store.joints()[i];
    JointRow& r = rows_[i];
    JointFrame& f = frames_[i];
    r = JointRow{};
    r.joint = i;
    r.type = j.type;
    if (j.broken) return;
    const Side A = sideOf(in.storage, in.contacts, j.bodyA, in.coupling.bodies[2 * i], j.localAnchorA);
    const Side B = sideOf(in.storage, in.contacts, j.bodyB, in.coupling.bodies[2 * i + 1], j.localAnchorB);
    if (!A.dynamic && !B.dynamic) return;
    const float h = in.h;
    const bool warm = in.warm;
    r.dynamicA = A.dynamic, r.dynamicB = B.dynamic;
    r.rowA = A.row, r.rowB = B.row;
    r.invMassA = A.invMass, r.invMassB = B.invMass;
    r.inertiaA = A.inertia, r.inertiaB = B.inertia;
    r.rA = f.rA = A.r, r.rB = f.rB = B.r;
    f.centres = B.com - A.com;
    const Vec3 separation = f.centres + B.r - A.r;
    Softness softness{in.rigid.biasRate, in.rigid.massScale, in.rigid.impulseScale};

    if (j.type == JointType::Distance || j.type == JointType::Spring) {
        const float len = length(separation);
        if (!(len > 1e-6f)) return;  // coincident anchors: no line to act along (only a spring's rest)
        r.axis = separation * (1.0f / len);
        f.length = j.length;
        if (j.type == JointType::Spring) {
            // A spring's softness is built on its effective mass: taken once, here (a distance joint's follows the
            // anchors, in beginRow()).
            const float K = axialK(r);
            if (!(K > 0)) return;
            if (!(j.damping + h * j.stiffness > 0)) return;  // neither stiffness nor damping: no force
            r.axialMass = 1.0f / K;
            softness = spring(j.stiffness, j.damping, K, h);
        }
        if (warm) r.axialImpulse = dot(j.linearImpulse, r.axis);
    } else if (warm) {
        r.linearImpulse = j.linearImpulse;
    }

    if (j.type == JointType::Hinge) {
        const Vec3 axisA = rotate(A.q, j.localAxisA);
        f.axisA = r.hingeAxis = axisA;
        f.axisB = rotate(B.q, j.localAxisB);
        perpendiculars(axisA, r.t1, r.t2);
        f.t1 = r.t1, f.t2 = r.t2;
        const JointSym3 inertia = sum(r.inertiaA, r.inertiaB);
        const float k11 = angularMass(inertia, r.t1, r.t1), k22 = angularMass(inertia, r.t2, r.t2);
        const float k12 = angularMass(inertia, r.t1, r.t2);
        const float det = k11 * k22 - k12 * k12;
        if (det > 0) {
            r.angularMass[0] = k22 / det, r.angularMass[1] = k11 / det, r.angularMass[2] = -k12 / det;
        }
        const float kAxis = angularMass(inertia, axisA, axisA);
        r.axisMass = kAxis > 0 ? 1.0f / kAxis : 0.0f;
        r.limit = j.enableLimit;
        r.motor = j.enableMotor;
        if (r.limit) {
            f.orientationA = A.q;
            f.orientationBReference = B.q * conjugate(j.referenceRotation);
            f.localAxisA = j.localAxisA;
            f.lowerAngle = j.lowerAngle, f.upperAngle = j.upperAngle;
        }
        r.motorSpeed = j.motorSpeed;
        r.maxMotorImpulse = j.maxMotorTorque * h;
        if (warm) {
            r.angularImpulse1 = dot(j.angularImpulse, r.t1);
            r.angularImpulse2 = dot(j.angularImpulse, r.t2);
            r.lowerImpulse = r.limit ? j.lowerImpulse : 0.0f;
            r.upperImpulse = r.limit ? j.upperImpulse : 0.0f;
            r.motorImpulse = r.motor ? j.motorImpulse : 0.0f;
        }
    }
    r.biasRate = softness.biasRate, r.massScale = softness.massScale, r.impulseScale = softness.impulseScale;
    r.active = true;
}

void JointSolver::buildBatch(BallJointBatch& b, std::uint32_t first, std::uint32_t count, std::int32_t stillRow,
                             const BuildInputs& in) const {
    // The lanes' poses gathered one by one (the bodies lie anywhere in the store), the rest in SIMD lanes.
    const std::vector<Joint>& joints = in.store.joints();
    const MovingBodies& m = in.storage.moving;
    const StaticBodies& statics = in.storage.statics;
    BallJointPoses poses{};
    for (std::uint32_t lane = 0; lane < kBatchLanes; ++lane) {
        b.joint[lane] = ~0u;
        b.bodyA[lane] = b.bodyB[lane] = stillRow;
        b.impulseX[lane] = b.impulseY[lane] = b.impulseZ[lane] = 0;
        if (lane >= count) {  // an empty lane: the still row on both sides, no geometry, no mass, no impulse
            poses.qw[0][lane] = poses.qw[1][lane] = 1;
            continue;
        }
        const std::uint32_t i = segmentRows_[first + lane];
        const Joint& j = joints[i];
        b.joint[lane] = i;
        if (in.warm)
            b.impulseX[lane] = j.linearImpulse.x, b.impulseY[lane] = j.linearImpulse.y,
            b.impulseZ[lane] = j.linearImpulse.z;
        for (int side = 0; side < 2; ++side) {
            const std::uint32_t coupled = in.coupling.bodies[2 * i + static_cast<std::uint32_t>(side)];
            const Vec3 local = side == 0 ? j.localAnchorA : j.localAnchorB;
            if (coupled == kNoCoupledBody) {  // static: its origin is its centre of mass
                const std::uint32_t d = in.storage.find(side == 0 ? j.bodyA : j.bodyB)->dense;
                poses.px[side][lane] = statics.px[d], poses.py[side][lane] = statics.py[d],
                poses.pz[side][lane] = statics.pz[d];
                poses.qx[side][lane] = statics.qx[d], poses.qy[side][lane] = statics.qy[d],
                poses.qz[side][lane] = statics.qz[d], poses.qw[side][lane] = statics.qw[d];
                poses.ax[side][lane] = local.x, poses.ay[side][lane] = local.y, poses.az[side][lane] = local.z;
                continue;
            }
            const std::uint32_t d = coupled;
            poses.px[side][lane] = m.px[d], poses.py[side][lane] = m.py[d], poses.pz[side][lane] = m.pz[d];
            poses.qx[side][lane] = m.qx[d], poses.qy[side][lane] = m.qy[d], poses.qz[side][lane] = m.qz[d],
            poses.qw[side][lane] = m.qw[d];
            poses.ax[side][lane] = local.x - m.lcx[d], poses.ay[side][lane] = local.y - m.lcy[d],
            poses.az[side][lane] = local.z - m.lcz[d];
            const std::int32_t row = in.contacts.solverIndexOf(d);
            (side == 0 ? b.bodyA : b.bodyB)[lane] = row >= 0 ? row : stillRow;
        }
    }
    ball_joint_kernels::build<simd::FloatW>(b, poses);
}

void JointSolver::beginRow(JointRow& r, const JointFrame& f, SolverBodies& rows, bool warm) const {
    if (!r.active) return;
    // The bodies' rotations since the step's start, as unit quaternions: the motion rows hold 2 x their vector part
    // (ContactSolver::loadBodies), w >= 0.
    const auto motionOf = [&](std::int32_t row, Quat& rotation) {
        if (row < 0) return Vec3{};
        const BodyRow& motion = rows.motion[static_cast<std::size_t>(row)];
        const Vec3 u = motion.angular * 0.5f;
        rotation = {u.x, u.y, u.z, std::sqrt(std::max(0.0f, 1.0f - dot(u, u)))};
        return motion.linear;
    };
    Quat rotationA, rotationB;
    const Vec3 displacementA = motionOf(r.rowA, rotationA), displacementB = motionOf(r.rowB, rotationB);
    r.rA = rotate(rotationA, f.rA);
    r.rB = rotate(rotationB, f.rB);
    const Vec3 separation = f.centres + (displacementB - displacementA) + (r.rB - r.rA);
    // Effective masses at this substep's anchors: a light body on a long lever turns its anchor far within a step,
    // and the step's first masses would then push the wrong way (springs keep theirs: their softness is built on it).
    if (r.type == JointType::Distance || r.type == JointType::Spring) {
        const float len = length(separation);
        if (len > 1e-6f) r.axis = separation * (1.0f / len);  // else the last direction stands
        r.axialError = len - f.length;
        if (r.type == JointType::Distance) {
            const float K = axialK(r);
            if (K > 0) r.axialMass = 1.0f / K;
        }
    } else {
        r.pointError = separation;
        r.pointMass = pointMassOf(r);
    }
    if (r.type == JointType::Hinge) {
        r.hingeAxis = rotate(rotationA, f.axisA);
        r.t1 = rotate(rotationA, f.t1);
        r.t2 = rotate(rotationA, f.t2);
        // The small rotation that would carry A's axis onto B's, along t1 and t2.
        const Vec3 misalignment = cross(r.hingeAxis, rotate(rotationB, f.axisB));
        r.angularError[0] = dot(misalignment, r.t1);
        r.angularError[1] = dot(misalignment, r.t2);
        if (r.limit) {
            const float angle =
                hingeAngleOf(rotationA * f.orientationA, rotationB * f.orientationBReference, Quat{}, f.localAxisA);
            r.lowerError = angle - f.lowerAngle;
            r.upperError = f.upperAngle - angle;
        }
    }
    if (!warm) {
        r.linearImpulse = {};
        r.axialImpulse = r.angularImpulse1 = r.angularImpulse2 = 0;
        r.lowerImpulse = r.upperImpulse = r.motorImpulse = 0;
        return;
    }
    Bodies s(r, rows);
    if (r.type == JointType::Distance || r.type == JointType::Spring)
        s.applyLinear(r.axis * r.axialImpulse);
    else
        s.applyLinear(r.linearImpulse);
    if (r.type == JointType::Hinge)
        s.applyAngular(r.t1 * r.angularImpulse1 + r.t2 * r.angularImpulse2 +
                       r.hingeAxis * (r.motorImpulse + r.lowerImpulse - r.upperImpulse));
    s.store(rows);
}

template <class Batch, class Row>
void JointSolver::forEachJoint(std::uint32_t segment, SolverBodies& rows, TaskPool* pool, Batch&& batch, Row&& row) {
    if (segment + 1 >= segmentStart_.size()) return;
    const bool coloured = segment + 2 == segmentStart_.size() && !colours_.empty();
    if (!coloured) {
        for (std::uint32_t i = segmentStart_[segment]; i < segmentStart_[segment + 1]; ++i) row(segmentRows_[i]);
        return;
    }
    const auto bodyRowsFor = [&](int worker) {
        return BodyRows{rows.velocity.data(), rows.motion.data(), rows.pseudo.data(), rows.mass.data(),
                        static_cast<std::int32_t>(rows.count + 1 + static_cast<std::uint32_t>(worker))};
    };
    // A colour's joints share no moving body: any thread may run any of them, in any order. The overflow colour's do
    // share, and run in order on one thread.
    const auto runColour = [&](const Colour& c, TaskPool* across) {
        const auto runBatches = [&](std::size_t, std::size_t begin, std::size_t end, int worker) {
            const BodyRows bodyRows = bodyRowsFor(worker);
            for (std::size_t k = begin; k < end; ++k) batch(batches_[c.firstBatch + k], bodyRows);
        };
        const auto runRows = [&](std::size_t, std::size_t begin, std::size_t end, int) {
            for (std::size_t i = c.first + begin; i < c.first + end; ++i) row(segmentRows_[i]);
        };
        const bool parallel = across != nullptr && !c.overflow;
        if (c.batchCount > 0) {
            if (parallel)
                across->forChunks(c.batchCount, kBatchChunk, runBatches);
            else
                runBatches(0, 0, c.batchCount, 0);
        }
        if (c.last > c.first) {
            if (parallel)
                across->forChunks(c.last - c.first, kColourChunk, runRows);
            else
                runRows(0, 0, c.last - c.first, 0);
        }
    };
    const auto runGroup = [&](const Group& g, TaskPool* across) {
        for (std::uint32_t c = g.firstColour; c < g.firstColour + g.colourCount; ++c) runColour(colours_[c], across);
    };
    if (groups_.size() == 1) {
        runGroup(groups_[0], pool);
        return;
    }
    // Two slabs, one task each (they share no moving body), then the joints that cross them.
    const auto runSlab = [&](std::size_t slab, std::size_t, std::size_t, int worker) {
        const BodyRows bodyRows = bodyRowsFor(worker);
        const Group& g = groups_[slab];
        for (std::uint32_t c = g.firstColour; c < g.firstColour + g.colourCount; ++c) {
            const Colour& colour = colours_[c];
            for (std::uint32_t k = 0; k < colour.batchCount; ++k) batch(batches_[colour.firstBatch + k], bodyRows);
            for (std::uint32_t i = colour.first; i < colour.last; ++i) row(segmentRows_[i]);
        }
    };
    if (pool != nullptr)
        pool->forChunks(2, 1, runSlab);
    else
        for (std::size_t slab = 0; slab < 2; ++slab) runSlab(slab, 0, 0, 0);
    runGroup(groups_[2], pool);
}

void JointSolver::beginSubstep(SolverBodies& rows, bool warm, std::uint32_t segment, TaskPool* pool) {
    forEachJoint(
        segment, rows, pool,
        [&](BallJointBatch& b, const BodyRows& bodyRows) {
            ball_joint_kernels::begin<simd::FloatW>(b, 0, bodyRows, warm);
        },
        [&](std::uint32_t i) { beginRow(rows_[i], frames_[i], rows, warm); });
}

namespace {

/// One side of a hinge limit: C = error >= 0 along `sign` * axis, impulse >= 0. A limit not yet reached lets the
/// bodies approach it by the error within the substep (speculative), so they arrive without overshoot.
void solveLimit(Bodies& s, const JointRow& r, float error, float sign, float& accumulated, float invH, bool useBias) {
    const float speed = sign * dot(r.hingeAxis, s.angularVelocity());
    float bias = 0, massScale = 1, impulseScale = 0;
    if (error > 0) {
        bias = error * invH;
    } else if (useBias) {
        bias = r.biasRate * error, massScale = r.massScale, impulseScale = r.impulseScale;
    }
    const float impulse = -massScale * r.axisMass * (speed + bias) - impulseScale * accumulated;
    const float total = std::max(accumulated + impulse, 0.0f);
    const float applied = total - accumulated;
    accumulated = total;
    s.applyAngular(r.hingeAxis * (sign * applied));
}

}  // namespace

void JointSolver::solveRow(JointRow& r, SolverBodies& rows, bool useBias, float invH) {
    if (!r.active) return;
    const bool isSpring = r.type == JointType::Spring;
    if (isSpring && !useBias) return;
    // Relaxing (no bias) makes the rigid rows hard and unbiased; springs keep their softness always.
    const bool biased = useBias || isSpring;
    const float biasRate = biased ? r.biasRate : 0.0f;
    const float massScale = biased ? r.massScale : 1.0f;
    const float impulseScale = biased ? r.impulseScale : 0.0f;
    Bodies s(r, rows);

    if (r.type == JointType::Hinge) {
        if (r.motor) {
            const float speed = dot(r.hingeAxis, s.angularVelocity());
            const float old = r.motorImpulse;
            r.motorImpulse =
                std::clamp(old - r.axisMass * (speed - r.motorSpeed), -r.maxMotorImpulse, r.maxMotorImpulse);
            s.applyAngular(r.hingeAxis * (r.motorImpulse - old));
        }
        if (r.limit) {
            solveLimit(s, r, r.lowerError, 1.0f, r.lowerImpulse, invH, useBias);
            solveLimit(s, r, r.upperError, -1.0f, r.upperImpulse, invH, useBias);
        }
        const Vec3 w = s.angularVelocity();
        const float c1 = dot(r.t1, w) + biasRate * r.angularError[0];
        const float c2 = dot(r.t2, w) + biasRate * r.angularError[1];
        const float l1 =
            -massScale * (r.angularMass[0] * c1 + r.angularMass[2] * c2) - impulseScale * r.angularImpulse1;
        const float l2 =
            -massScale * (r.angularMass[2] * c1 + r.angularMass[1] * c2) - impulseScale * r.angularImpulse2;
        r.angularImpulse1 += l1;
        r.angularImpulse2 += l2;
        s.applyAngular(r.t1 * l1 + r.t2 * l2);
    }

    if (r.type == JointType::Distance || isSpring) {
        const float speed = dot(r.axis, s.pointVelocity());
        const float impulse =
            -massScale * r.axialMass * (speed + biasRate * r.axialError) - impulseScale * r.axialImpulse;
        r.axialImpulse += impulse;
        s.applyLinear(r.axis * impulse);
    } else {
        const Vec3 rhs = s.pointVelocity() + r.pointError * biasRate;
        const Vec3 impulse = (r.pointMass * rhs) * -massScale - r.linearImpulse * impulseScale;
        r.linearImpulse += impulse;
        s.applyLinear(impulse);
    }
    s.store(rows);
}

void JointSolver::solve(SolverBodies& rows, bool useBias, std::uint32_t segment, TaskPool* pool) {
    const float invH = 1.0f / h_;
    const BallJointSoftness softness = useBias ? rigid_ : BallJointSoftness{};
    forEachJoint(
        segment, rows, pool,
        [&](BallJointBatch& b, const BodyRows& bodyRows) {
            ball_joint_kernels::solve<simd::FloatW>(b, 0, bodyRows, softness);
        },
        [&](std::uint32_t i) { solveRow(rows_[i], rows, useBias, invH); });
}

void JointSolver::partition(const ContactSolver& contacts, const MovingBodies& m, std::uint32_t segments) {
    // Counting sort of the active joints by segment, stable so that each segment keeps the store order.
    segmentStart_.assign(segments + 1, 0);
    for (const JointLink& l : links_)
        if (l.segment != kInactive) ++segmentStart_[l.segment + 1];
    for (std::uint32_t k = 0; k < segments; ++k) segmentStart_[k + 1] += segmentStart_[k];
    segmentRows_.resize(segmentStart_[segments]);
    segmentFill_.assign(segmentStart_.begin(), segmentStart_.end() - 1);
    for (std::uint32_t i = 0; i < links_.size(); ++i)
        if (links_[i].segment != kInactive) segmentRows_[segmentFill_[links_[i].segment]++] = i;
    colourLarge(contacts, m);
}

void JointSolver::colourLarge(const ContactSolver& contacts, const MovingBodies& m) {
    colours_.clear();
    groups_.clear();
    batches_.clear();
    batchJoints_.clear();
    batchedJoints_ = 0;
    const std::size_t large = segmentStart_.size() - 2;
    const std::uint32_t begin = segmentStart_[large], count = segmentStart_[large + 1] - begin;
    if (count < kColouredJoints) return;
    // Two slabs when the joints split cleanly across the middle of the island (a sheet, a lattice, a bridge): each
    // slab's colours then run whole in one task per pass, and only the joints that cross the cut colour by colour
    // after them, so a pass costs one wait for the threads instead of one per colour. The cut: across the longest
    // side of the box around the joints' bodies, at the median of the joints' lowest body; a joint lies on the side
    // of the cut where all its dynamic bodies lie, or crosses. Made from this step's places and kept with the rest
    // of the layout: a slab's joints share no moving body with the other slab's however the bodies move after.
    const std::vector<std::uint32_t>& denseOfRow = contacts.bodies().moving;
    const auto place = [&](std::int32_t row) {
        const std::uint32_t d = denseOfRow[static_cast<std::size_t>(row)];
        return Vec3{m.px[d], m.py[d], m.pz[d]};
    };
    Vec3 lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    for (std::uint32_t i = 0; i < count; ++i) {
        const JointLink& l = links_[segmentRows_[begin + i]];
        const Vec3 p = place(l.dynamicA ? l.rowA : l.rowB);
        lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
        hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
    }
    const Vec3 extent = hi - lo;
    const int axis = extent.x >= extent.y && extent.x >= extent.z ? 0 : (extent.y >= extent.z ? 1 : 2);
    const float* coordinate = axis == 0 ? m.px.data() : (axis == 1 ? m.py.data() : m.pz.data());
    const auto along = [&](std::int32_t row) { return coordinate[denseOfRow[static_cast<std::size_t>(row)]]; };
    const auto lowest = [&](const JointLink& l) {
        return l.dynamicA && l.dynamicB ? std::min(along(l.rowA), along(l.rowB)) : along(l.dynamicA ? l.rowA : l.rowB);
    };
    slabKeys_.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) slabKeys_[i] = lowest(links_[segmentRows_[begin + i]]);
    const auto middle = slabKeys_.begin() + count / 2;
    std::nth_element(slabKeys_.begin(), middle, slabKeys_.end());
    const float cut = *middle;
    std::uint32_t sizes[3] = {};
    const auto groupOf = [&](const JointLink& l) {
        const bool belowA = !l.dynamicA || along(l.rowA) < cut, belowB = !l.dynamicB || along(l.rowB) < cut;
        const bool aboveA = !l.dynamicA || along(l.rowA) >= cut, aboveB = !l.dynamicB || along(l.rowB) >= cut;
        return belowA && belowB ? 0u : (aboveA && aboveB ? 1u : 2u);
    };
    for (std::uint32_t i = 0; i < count; ++i) ++sizes[groupOf(links_[segmentRows_[begin + i]])];
    const bool slabs = sizes[2] <= count / kMaxCrossingShare && std::min(sizes[0], sizes[1]) >= count / 4;
    // Each group in store order, one after the other: slab 0, slab 1, the crossing joints; or all as one.
    orderScratch_.resize(count);
    std::uint32_t fill[3] = {0, sizes[0], sizes[0] + sizes[1]};
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::uint32_t row = segmentRows_[begin + i];
        orderScratch_[slabs ? fill[groupOf(links_[row])]++ : i] = row;
    }
    std::copy(orderScratch_.begin(), orderScratch_.end(), segmentRows_.begin() + begin);
    std::uint32_t batchCount = 0;
    if (slabs) {
        colourGroup(contacts, begin, sizes[0], batchCount);
        colourGroup(contacts, begin + sizes[0], sizes[1], batchCount);
        colourGroup(contacts, begin + sizes[0] + sizes[1], sizes[2], batchCount);
    } else {
        colourGroup(contacts, begin, count, batchCount);
    }
    batches_.resize(batchCount);
}

void JointSolver::colourGroup(const ContactSolver& contacts, std::uint32_t begin, std::uint32_t count,
                              std::uint32_t& batchCount) {
    // Greedy, in store order: each joint takes the first colour neither of its moving bodies has yet. Within a
    // colour the ball joints come first (they go into batches), each kind in store order.
    groups_.push_back({static_cast<std::uint32_t>(colours_.size()), 0});
    bodyColours_.assign(contacts.bodies().count, 0);
    colourOf_.resize(count);
    constexpr std::uint32_t kColourSlots = kMaxJointColours + 1;
    std::uint32_t balls[kColourSlots] = {}, others[kColourSlots] = {};
    const auto batched = [](const JointLink& l, std::uint32_t colour) {
        return l.ball && colour != kJointOverflowColour;
    };
    for (std::uint32_t i = 0; i < count; ++i) {
        const JointLink& l = links_[segmentRows_[begin + i]];
        std::uint64_t* a = l.dynamicA ? &bodyColours_[static_cast<std::size_t>(l.rowA)] : nullptr;
        std::uint64_t* b = l.dynamicB ? &bodyColours_[static_cast<std::size_t>(l.rowB)] : nullptr;
        const std::uint64_t used = (a ? *a : 0) | (b ? *b : 0);
        std::uint32_t colour = static_cast<std::uint32_t>(std::countr_one(used));
        if (colour >= kMaxJointColours) {
            colour = kJointOverflowColour;
        } else {
            if (a) *a |= std::uint64_t{1} << colour;
            if (b) *b |= std::uint64_t{1} << colour;
        }
        colourOf_[i] = static_cast<std::uint8_t>(colour);
        ++(batched(l, colour) ? balls : others)[colour];
    }
    std::uint32_t ballFill[kColourSlots], otherFill[kColourSlots];
    std::uint32_t at = 0;
    for (std::uint32_t c = 0; c < kColourSlots; ++c) {
        if (balls[c] + others[c] == 0) continue;
        Colour colour;
        colour.firstBatch = batchCount;
        colour.batchCount = static_cast<std::uint32_t>((balls[c] + kBatchLanes - 1) / kBatchLanes);
        colour.firstBall = begin + at;
        colour.first = begin + at + balls[c];
        colour.last = colour.first + others[c];
        colour.overflow = c == kJointOverflowColour;
        ballFill[c] = at;
        otherFill[c] = at + balls[c];
        at += balls[c] + others[c];
        for (std::uint32_t k = 0; k < colour.batchCount; ++k)
            batchJoints_.push_back({colour.firstBall + k * static_cast<std::uint32_t>(kBatchLanes),
                                    std::min<std::uint32_t>(balls[c] - k * static_cast<std::uint32_t>(kBatchLanes),
                                                            static_cast<std::uint32_t>(kBatchLanes))});
        batchCount += colour.batchCount;
        batchedJoints_ += balls[c];
        colours_.push_back(colour);
    }
    orderScratch_.resize(count);
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::uint32_t row = segmentRows_[begin + i], colour = colourOf_[i];
        JointLink& l = links_[row];
        l.batched = batched(l, colour);
        orderScratch_[l.batched ? ballFill[colour]++ : otherFill[colour]++] = row;
    }
    std::copy(orderScratch_.begin(), orderScratch_.end(), segmentRows_.begin() + begin);
    groups_.back().colourCount = static_cast<std::uint32_t>(colours_.size()) - groups_.back().firstColour;
}

void JointSolver::finish(JointStore& store, TaskPool& pool) {
    std::vector<Joint>& joints = store.joints();
    const float invH = 1.0f / h_;
    // Reactions in parallel; the joints that break are marked after, in store order.
    breaking_.assign(joints.size(), 0);
    std::atomic<bool> anyBreaks{false};
    const auto react = [&](std::uint32_t i, Vec3 linear, Vec3 angular, Vec3 axial) {
        Joint& j = joints[i];
        j.linearImpulse = linear;
        j.angularImpulse = angular;
        j.reactionForce = linear * invH;
        j.reactionTorque = (angular + axial) * invH;
        if (length(j.reactionForce) > j.breakForce || length(j.reactionTorque) > j.breakTorque) {
            breaking_[i] = 1;
            anyBreaks.store(true, std::memory_order_relaxed);
        }
    };
    pool.forChunks(rows_.size(), kJointChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t i = begin; i < end; ++i) {
            if (links_[i].batched) continue;
            const JointRow& r = rows_[i];
            Joint& j = joints[i];
            if (j.broken) continue;
            if (!r.active) {
                j.linearImpulse = j.angularImpulse = {};
                j.lowerImpulse = j.upperImpulse = j.motorImpulse = 0;
                j.reactionForce = j.reactionTorque = {};
                continue;
            }
            const bool axial = r.type == JointType::Distance || r.type == JointType::Spring;
            j.lowerImpulse = r.lowerImpulse, j.upperImpulse = r.upperImpulse, j.motorImpulse = r.motorImpulse;
            react(static_cast<std::uint32_t>(i), axial ? r.axis * r.axialImpulse : r.linearImpulse,
                  r.t1 * r.angularImpulse1 + r.t2 * r.angularImpulse2,
                  r.hingeAxis * (r.motorImpulse + r.lowerImpulse - r.upperImpulse));
        }
    });
    pool.forChunks(batches_.size(), kBatchChunk, [&](std::size_t, std::size_t begin, std::size_t end, int) {
        for (std::size_t k = begin; k < end; ++k) {
            const BallJointBatch& b = batches_[k];
            for (std::size_t lane = 0; lane < kBatchLanes; ++lane)
                if (b.joint[lane] != ~0u)
                    react(b.joint[lane], {b.impulseX[lane], b.impulseY[lane], b.impulseZ[lane]}, {}, {});
        }
    });
    if (!anyBreaks.load()) return;
    for (std::uint32_t i = 0; i < joints.size(); ++i) {
        if (breaking_[i] == 0) continue;
        store.markBroken(i);
        Joint& j = joints[i];
        j.linearImpulse = j.angularImpulse = {};
        j.lowerImpulse = j.upperImpulse = j.motorImpulse = 0;
        rows_[i].active = false;
    }
}

}  // namespace rubble::detail
