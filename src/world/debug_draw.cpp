// Debug draw: the default line drawings of DebugDraw's solid calls, and World::debugDraw, which walks the bodies,
// their shapes (compound children, hull edges, mesh and heightfield triangles), the last step's contacts and broad
// phase, and the joints.
#include "rubble/debug_draw.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "broadphase/multi_resolution_grid.h"
#include "broadphase/static_bvh.h"
#include "world/world_impl.h"

namespace rubble {

namespace {

constexpr int kCircleSegments = 16;

Transform compose(const Transform& outer, const Transform& inner) {
    return {apply(outer, inner.position), outer.rotation * inner.rotation};
}

/// Circle of `radius` about `center` in the plane spanned by the pose's local axes u and v.
void circle(DebugDraw& draw, const Transform& pose, Vec3 center, Vec3 u, Vec3 v, float radius, float fromAngle,
            float toAngle, DebugColor color) {
    Vec3 previous{};
    for (int i = 0; i <= kCircleSegments; ++i) {
        const float t = fromAngle + (toAngle - fromAngle) * static_cast<float>(i) / kCircleSegments;
        const Vec3 local = center + u * (radius * std::cos(t)) + v * (radius * std::sin(t));
        const Vec3 p = apply(pose, local);
        if (i > 0) draw.line(previous, p, color);
        previous = p;
    }
}

}  // namespace

void DebugLineBatch::line(Vec3 a, Vec3 b, DebugColor color) {
    lines.points.push_back(a);
    lines.points.push_back(b);
    lines.colors.push_back(color);
}

void DebugDraw::triangle(Vec3 a, Vec3 b, Vec3 c, DebugColor color) {
    line(a, b, color);
    line(b, c, color);
    line(c, a, color);
}

void DebugDraw::point(Vec3 p, float size, DebugColor color) {
    const float h = size * 0.5f;
    line(p - Vec3{h, 0, 0}, p + Vec3{h, 0, 0}, color);
    line(p - Vec3{0, h, 0}, p + Vec3{0, h, 0}, color);
    line(p - Vec3{0, 0, h}, p + Vec3{0, 0, h}, color);
}

void DebugDraw::box(const Transform& pose, Vec3 e, DebugColor color) {
    Vec3 corner[8];
    for (int i = 0; i < 8; ++i)
        corner[i] = apply(pose, {(i & 1) ? e.x : -e.x, (i & 2) ? e.y : -e.y, (i & 4) ? e.z : -e.z});
    // Corners differing in one bit of their index share an edge.
    for (int i = 0; i < 8; ++i)
        for (int bit = 1; bit < 8; bit <<= 1)
            if (!(i & bit)) line(corner[i], corner[i | bit], color);
}

void DebugDraw::aabb(Vec3 min, Vec3 max, DebugColor color) {
    const Vec3 center = (min + max) * 0.5f, half = (max - min) * 0.5f;
    box(Transform{center, Quat{}}, half, color);
}

void DebugDraw::sphere(const Transform& pose, float radius, DebugColor color) {
    const float full = 2 * std::numbers::pi_v<float>;
    circle(*this, pose, {}, {1, 0, 0}, {0, 1, 0}, radius, 0, full, color);
    circle(*this, pose, {}, {0, 1, 0}, {0, 0, 1}, radius, 0, full, color);
    circle(*this, pose, {}, {0, 0, 1}, {1, 0, 0}, radius, 0, full, color);
}

void DebugDraw::capsule(const Transform& pose, float radius, float halfHeight, DebugColor color) {
    const float pi = std::numbers::pi_v<float>;
    const Vec3 top{0, halfHeight, 0}, bottom{0, -halfHeight, 0};
    circle(*this, pose, top, {1, 0, 0}, {0, 0, 1}, radius, 0, 2 * pi, color);
    circle(*this, pose, bottom, {1, 0, 0}, {0, 0, 1}, radius, 0, 2 * pi, color);
    for (Vec3 side : {Vec3{radius, 0, 0}, Vec3{-radius, 0, 0}, Vec3{0, 0, radius}, Vec3{0, 0, -radius}})
        line(apply(pose, top + side), apply(pose, bottom + side), color);
    circle(*this, pose, top, {1, 0, 0}, {0, 1, 0}, radius, 0, pi, color);
    circle(*this, pose, top, {0, 0, 1}, {0, 1, 0}, radius, 0, pi, color);
    circle(*this, pose, bottom, {1, 0, 0}, {0, 1, 0}, radius, pi, 2 * pi, color);
    circle(*this, pose, bottom, {0, 0, 1}, {0, 1, 0}, radius, pi, 2 * pi, color);
}

namespace {

/// The island a moving body belonged to at the last step, for kDrawIslands; bodies added since have none yet.
std::optional<std::uint32_t> islandOf(const World::Impl& w, std::uint32_t movingIndex) {
    const std::vector<std::uint32_t>& of = w.islands.islandOf;
    if (movingIndex >= of.size() || of[movingIndex] == detail::kNoIsland) return std::nullopt;
    return of[movingIndex];
}

DebugColor islandColor(std::uint32_t island) {
    // A fixed hash spread over hues, so an island keeps its colour from frame to frame.
    const std::uint32_t h = island * 2654435761u;
    return {static_cast<std::uint8_t>(64 + (h >> 24) % 192), static_cast<std::uint8_t>(64 + (h >> 16) % 192),
            static_cast<std::uint8_t>(64 + (h >> 8) % 192), 255};
}

/// The pose of a body's origin (where BodyDef::position put it), which joint anchors are relative to; none for a
/// stale handle.
std::optional<Transform> poseOf(const World::Impl& w, BodyId id) {
    const detail::BodySlot* slot = w.bodies.find(id);
    if (slot == nullptr) return std::nullopt;
    const std::uint32_t i = slot->dense;
    if (slot->set == detail::BodySet::Static) {
        const detail::StaticBodies& s = w.bodies.statics;
        return Transform{{s.px[i], s.py[i], s.pz[i]}, {s.qx[i], s.qy[i], s.qz[i], s.qw[i]}};
    }
    const detail::MovingBodies& m = w.bodies.moving;
    const Quat q = w.orientationOf(i);
    return Transform{w.comOf(i) - rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]}), q};
}

struct Drawer {
    const World::Impl& w;
    DebugDraw& draw;
    const DebugDrawOptions& options;
    std::uint32_t trianglesLeft;
    std::uint32_t boxesLeft;

    bool inRegion(Vec3 min, Vec3 max) const {
        if (!options.regionMin || !options.regionMax) return true;
        const Vec3 rmin = *options.regionMin, rmax = *options.regionMax;
        return min.x <= rmax.x && rmin.x <= max.x && min.y <= rmax.y && rmin.y <= max.y && min.z <= rmax.z &&
               rmin.z <= max.z;
    }

    void triangle(const Transform& pose, Vec3 a, Vec3 b, Vec3 c, DebugColor color) {
        if (trianglesLeft == 0) return;
        const Vec3 wa = apply(pose, a), wb = apply(pose, b), wc = apply(pose, c);
        const Vec3 min{std::min({wa.x, wb.x, wc.x}), std::min({wa.y, wb.y, wc.y}), std::min({wa.z, wb.z, wc.z})};
        const Vec3 max{std::max({wa.x, wb.x, wc.x}), std::max({wa.y, wb.y, wc.y}), std::max({wa.z, wb.z, wc.z})};
        if (!inRegion(min, max)) return;
        draw.triangle(wa, wb, wc, color);
        --trianglesLeft;
    }

    void shape(const detail::Shape& s, const Transform& pose, DebugColor color) {
        using detail::ShapeKind;
        switch (s.kind) {
            case ShapeKind::Sphere:
                draw.sphere(pose, s.radius, color);
                break;
            case ShapeKind::Box:
                draw.box(pose, s.halfExtents, color);
                break;
            case ShapeKind::Capsule:
                draw.capsule(pose, s.radius, s.halfHeight, color);
                break;
            case ShapeKind::ConvexHull: {
                const detail::ConvexHull& hull = *s.hull;
                for (std::size_t e = 0; e + 1 < hull.edges.size(); e += 2)
                    draw.line(apply(pose, hull.vertices[hull.edges[e]]), apply(pose, hull.vertices[hull.edges[e + 1]]),
                              color);
                break;
            }
            case ShapeKind::Compound:
                for (const detail::CompoundChild& child : s.children)
                    shape(*child.shape, compose(pose, child.local), color);
                break;
            case ShapeKind::TriangleMesh:
                if (options.flags & kDrawMeshTriangles) {
                    const detail::TriangleMesh& mesh = *s.mesh;
                    for (std::uint32_t t = 0; t < mesh.triangleCount() && trianglesLeft > 0; ++t)
                        triangle(pose, mesh.vertices[mesh.indices[3 * t]], mesh.vertices[mesh.indices[3 * t + 1]],
                                 mesh.vertices[mesh.indices[3 * t + 2]], color);
                }
                break;
            case ShapeKind::Heightfield:
                if (options.flags & kDrawMeshTriangles) {
                    const detail::Heightfield& field = *s.heightfield;
                    const std::uint32_t count = detail::heightfieldTriangleCount(field);
                    for (std::uint32_t t = 0; t < count && trianglesLeft > 0; ++t) {
                        const auto v = detail::heightfieldTriangle(field, t);
                        triangle(pose, v[0], v[1], v[2], color);
                    }
                }
                break;
        }
    }

    /// Draws a broad-phase box unless it lies outside the region or the cap is spent; false once the cap is spent.
    bool broadphaseBox(Vec3 min, Vec3 max, DebugColor color) {
        if (boxesLeft == 0) return false;
        if (inRegion(min, max)) {
            draw.aabb(min, max, color);
            --boxesLeft;
        }
        return true;
    }

    void gridCells() {
        const auto& levels = options.colors.gridLevels;
        w.broadPhase.grid().forEachCell([&](const detail::MultiResolutionGrid::CellBox& cell) {
            const Vec3 min{static_cast<float>(cell.min[0]), static_cast<float>(cell.min[1]),
                           static_cast<float>(cell.min[2])};
            const Vec3 max{static_cast<float>(cell.max[0]), static_cast<float>(cell.max[1]),
                           static_cast<float>(cell.max[2])};
            return broadphaseBox(min, max, levels[static_cast<std::size_t>(cell.level) % levels.size()]);
        });
    }

    /// The node boxes of the top `depth` levels below the root, breadth first, so that the cap cuts the deepest.
    void treeNodes(const detail::StaticBvh::Tree& tree, std::uint32_t depth) {
        using detail::StaticBvh;
        if (tree.nodes.empty() || depth == 0) return;
        std::vector<std::uint32_t> level{0}, next;
        for (std::uint32_t d = 0; d < depth && !level.empty(); ++d) {
            next.clear();
            for (std::uint32_t node : level)
                for (int k = 0; k < 4; ++k) {
                    const std::uint32_t child = tree.nodes[node].child(k);
                    // Primitives are bodies and triangles, which the shape and AABB layers draw.
                    if (child == StaticBvh::kUnusedLane || (child & StaticBvh::kPrimitiveBit)) continue;
                    const detail::Aabb box = tree.nodes[node].box(k);
                    if (!(box.min.x <= box.max.x && box.min.y <= box.max.y && box.min.z <= box.max.z)) continue;
                    if (!broadphaseBox(box.min, box.max, options.colors.staticBvhNode)) return;
                    next.push_back(child);
                }
            std::swap(level, next);
        }
    }

    void joint(const detail::Joint& j, const Transform& poseA, const Transform& poseB) {
        const DebugDrawColors& c = options.colors;
        const DebugColor color = j.type == JointType::Distance ? c.distanceJoint
                                 : j.type == JointType::Spring ? c.springJoint
                                 : j.type == JointType::Ball   ? c.ballJoint
                                                               : c.hingeJoint;
        const Vec3 a = apply(poseA, j.localAnchorA), b = apply(poseB, j.localAnchorB);
        const Vec3 min{std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
        const Vec3 max{std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
        if (!inRegion(min, max)) return;
        draw.point(a, options.pointSize, color);
        draw.point(b, options.pointSize, color);
        draw.line(a, b, color);
        if (j.type != JointType::Hinge) return;
        const float size = options.jointSize;
        const Vec3 axis = j.localAxisA;  // unit, A's frame
        const Vec3 worldAxis = rotate(poseA.rotation, axis) * size;
        draw.line(a - worldAxis, a + worldAxis, color);
        if (!j.enableLimit) return;
        // Angles are measured about A's axis from a direction u perpendicular to it; the spoke turns u by B's
        // rotation relative to its pose at creation, qB conj(reference), which is u turned by the hinge angle.
        const Vec3 helper = std::fabs(axis.x) < 0.6f ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
        const Vec3 u = cross(cross(axis, helper), axis) * (1.0f / length(cross(axis, helper)));
        const Vec3 v = cross(axis, u);
        const Transform arcPose{a, poseA.rotation};
        circle(draw, arcPose, {}, u, v, size, j.lowerAngle, j.upperAngle, color);
        draw.line(a, a + rotate(poseB.rotation * conjugate(j.referenceRotation), u) * size, color);
    }

    void body(const detail::Shape& s, const Transform& pose, DebugColor color) {
        const detail::Aabb bounds = detail::worldBounds(s, pose);
        if (!inRegion(bounds.min, bounds.max)) return;
        if (options.flags & kDrawShapes) shape(s, pose, color);
        if (options.flags & kDrawAabbs) draw.aabb(bounds.min, bounds.max, options.colors.aabb);
    }
};

}  // namespace

void World::debugDraw(DebugDraw& draw, const DebugDrawOptions& options) const {
    const Impl& w = *impl_;
    Drawer drawer{w, draw, options, options.maxTriangles, options.maxBroadphaseBoxes};
    const DebugDrawColors& colors = options.colors;

    // Bodies are walked only for a layer that draws them: each costs a world bounds computation, which alone took
    // several ms of a cells-only draw of 100k bodies.
    const bool bodies = (options.flags & (kDrawShapes | kDrawAabbs)) != 0;
    const detail::StaticBodies& s = w.bodies.statics;
    for (std::uint32_t i = 0; bodies && i < s.size(); ++i)
        drawer.body(w.shapes[s.shape[i]], {{s.px[i], s.py[i], s.pz[i]}, {s.qx[i], s.qy[i], s.qz[i], s.qw[i]}},
                    colors.staticBody);

    const detail::MovingBodies& m = w.bodies.moving;
    for (std::uint32_t i = 0; bodies && i < m.size(); ++i) {
        const std::uint8_t flags = m.flags[i];
        DebugColor color = (flags & detail::kFlagKinematic) ? colors.kinematicBody : colors.dynamicBody;
        if (options.flags & kDrawIslands)
            if (const auto island = islandOf(w, i)) color = islandColor(*island);
        if ((options.flags & kDrawSleeping) && (flags & detail::kFlagAsleep)) color = colors.asleep;
        if (flags & detail::kFlagFrozen) color = colors.frozen;
        const Quat q = w.orientationOf(i);
        const Vec3 origin = w.comOf(i) - rotate(q, {m.lcx[i], m.lcy[i], m.lcz[i]});
        drawer.body(w.shapes[m.shape[i]], {origin, q}, color);
    }

    if (options.flags & kDrawBroadphaseCells) {
        // The profile names the algorithm that ran in the last step (Auto when no broad phase ran), so a grid kept
        // from an earlier step is never drawn as if it were current.
        if (w.profile.broadPhase == BroadPhaseKind::Grid) drawer.gridCells();
        if (options.broadphaseTreeDepth > 0 && w.broadPhase.staticPrimitiveCount() > 0) {
            // Through the queries' cache: it applies the static edits since the step and commits the tree once,
            // under its lock, so drawing never races a query that would otherwise do the same.
            const detail::QueryTrees& trees = impl_->queries.prepare(*impl_);
            for (const detail::StaticBvh::Tree* tree : trees.statics)
                if (tree != nullptr) drawer.treeNodes(*tree, options.broadphaseTreeDepth);
        }
    }

    if (options.flags & kDrawJoints) {
        std::uint32_t jointsLeft = options.maxJoints;
        for (const detail::Joint& j : w.joints.joints()) {
            if (jointsLeft == 0) break;
            if (j.broken) continue;
            const std::optional<Transform> poseA = poseOf(w, j.bodyA), poseB = poseOf(w, j.bodyB);
            if (!poseA || !poseB) continue;
            drawer.joint(j, *poseA, *poseB);
            --jointsLeft;
        }
    }

    if (options.flags & kDrawContacts) {
        // Contact points are kept in world space, so they stay drawable after bodies were removed since the step.
        for (const detail::Manifold& manifold : w.contacts.manifolds)
            for (int p = 0; p < manifold.pointCount; ++p) {
                const Vec3 at = manifold.points[p].position;
                if (!drawer.inRegion(at, at)) continue;
                draw.point(at, options.pointSize, colors.contactPoint);
                draw.line(at, at + manifold.normal * options.normalLength, colors.contactNormal);
            }
    }
}

}  // namespace rubble
