// Merging a body's triangle manifolds that share a normal; see mesh_manifolds.h.
#include "narrowphase/mesh_manifolds.h"

#include <algorithm>

#include "contacts/contacts.h"
#include "narrowphase/clip.h"
#include "narrowphase/triangle_pairs.h"

namespace rubble::detail {
namespace {

/// Most manifolds one merge pools: each brings at most kMaxManifoldPoints points.
constexpr int kMaxPooledManifolds = kClipCapacity / kMaxManifoldPoints;
/// A merged point's feature id that names a feature of its triangle is mixed with the triangle's index (Knuth's
/// multiplicative hash): each triangle's kernel numbers its own features, so the same id from two triangles names two
/// points. A body's own corner keeps its id from triangle to triangle.
constexpr std::uint32_t kTriangleFeatureMix = 0x9E3779B1u;

}  // namespace

std::size_t mergeTriangleManifolds(std::vector<ContactPair>& pairs, std::vector<Manifold>& manifolds,
                                   std::size_t first) {
    const std::size_t end = manifolds.size();
    if (end - first < 2) return end;
    std::size_t out = first;
    // Members of a group are marked by clearing their point count once pooled.
    for (std::size_t i = first; i < end; ++i) {
        if (manifolds[i].pointCount == 0) continue;
        const Vec3 n = manifolds[i].normal;
        Vec3 pooled[kClipCapacity];
        float depth[kClipCapacity];
        std::uint32_t feature[kClipCapacity];
        int count = 0, members = 0;
        std::uint32_t triangle = pairs[i].triangle;
        Vec3 normal = n;
        float deepest = -INFINITY;
        for (std::size_t j = i; j < end && members < kMaxPooledManifolds; ++j) {
            Manifold& m = manifolds[j];
            if (m.pointCount == 0 || (j != i && dot(m.normal, n) < kMergeNormalCosine)) continue;
            ++members;
            triangle = std::min(triangle, pairs[j].triangle);
            for (int k = 0; k < m.pointCount; ++k) {
                const ContactPoint& p = m.points[k];
                if (p.depth > deepest) deepest = p.depth, normal = m.normal;
                int same = 0;
                while (same < count) {
                    const Vec3 d = pooled[same] - p.position;
                    if (dot(d, d) < kMergePointDistance * kMergePointDistance) break;
                    ++same;
                }
                if (same < count) {
                    if (p.depth > depth[same]) pooled[same] = p.position, depth[same] = p.depth;
                    continue;
                }
                // A body's corner can also come from a second triangle as that triangle's lone deepest point, which
                // sits over the triangle, not at the corner: an id already taken is mixed with the triangle too.
                std::uint32_t id = p.feature;
                const auto taken = [&](std::uint32_t f) {
                    return std::find(feature, feature + count, f) != feature + count;
                };
                if (featureOfTriangle(id) || taken(id)) id ^= pairs[j].triangle * kTriangleFeatureMix;
                while (taken(id)) id = id * kTriangleFeatureMix + 1;
                pooled[count] = p.position, depth[count] = p.depth, feature[count] = id;
                ++count;
            }
            if (j != i) m.pointCount = 0;
        }
        Manifold merged;
        merged.normal = normal;
        if (members == 1) {
            merged = manifolds[i];
        } else {
            Vec3 u, v;
            planeBasis(normal, u, v);
            int chosen[4];
            const int kept = reduceContactPoints(pooled, depth, count, u, v, chosen);
            for (int k = 0; k < kept; ++k) merged.points[k] = {pooled[chosen[k]], depth[chosen[k]], feature[chosen[k]]};
            merged.pointCount = kept;
        }
        ContactPair pair = pairs[i];
        pair.triangle = triangle;
        pairs[out] = pair;
        manifolds[out] = merged;
        ++out;
    }
    pairs.resize(out);
    manifolds.resize(out);
    return out;
}

}  // namespace rubble::detail
