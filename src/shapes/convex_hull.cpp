// Convex hulls through qhull (reentrant API). Qhull's default 3-d merging gives the polygonal faces the collision
// code wants (a box has 6 faces, not 12 triangles); we then tidy each face so only true corners remain.
#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "rubble/error.h"
#include "shapes/shape.h"
#include "world/validation.h"

#include <libqhull_r/qhull_ra.h>

namespace rubble::detail {

namespace {

struct D3 {
    double x, y, z;
};
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double norm(D3 a) { return std::sqrt(dot(a, a)); }
D3 toD3(Vec3 v) { return {v.x, v.y, v.z}; }

constexpr const char* kDef = "ConvexHullDef";

// Relative size below which a cloud counts as flat. Float input carries ~1e-7 relative rounding, so clouds meant to
// be planar land far below this, while any solid a game would want is far above it.
constexpr double kFlatTolerance = 1e-5;

// Qhull would also refuse flat input, but with a message about its internals; checking first lets us say which
// degeneracy it is.
void requireVolume(const std::vector<Vec3>& points) {
    const std::string count = "the " + std::to_string(points.size()) + " points";
    const D3 p0 = toD3(points[0]);
    auto farthestFrom = [&](auto distance) {
        std::size_t best = 0;
        double bestDistance = -1;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const double d = distance(toD3(points[i]));
            if (d > bestDistance) bestDistance = d, best = i;
        }
        return std::pair{best, bestDistance};
    };
    const auto [ia, da0] = farthestFrom([&](D3 p) { return norm(p - p0); });
    if (!(da0 > 0)) fail(kDef, count + " are all the same point: a hull needs volume");
    const D3 a = toD3(points[ia]);
    const auto [ib, farthestLength] = farthestFrom([&](D3 p) { return norm(p - a); });
    const double length = farthestLength;  // a structured binding cannot be captured before C++20's clang 16
    const D3 b = toD3(points[ib]);
    const D3 axis = b - a;
    const auto [ic, lineDistance] = farthestFrom([&](D3 p) { return norm(cross(axis, p - a)) / length; });
    if (!(lineDistance > kFlatTolerance * length)) fail(kDef, count + " are collinear: a hull needs volume");
    D3 n = cross(axis, toD3(points[ic]) - a);
    const double nl = norm(n);
    n = {n.x / nl, n.y / nl, n.z / nl};
    const auto [id, planeDistance] = farthestFrom([&](D3 p) { return std::abs(dot(n, p - a)); });
    (void)id;
    if (!(planeDistance > kFlatTolerance * length)) fail(kDef, count + " are coplanar: a hull needs volume");
}

struct RawFace {
    std::vector<std::uint32_t> points;  // input point indices, unordered
    D3 normal;
};

// Owns one qhull run: its error stream and its memory are released however we leave.
class QhullRun {
public:
    QhullRun() : qh_(std::make_unique<qhT>()) {
        // Qhull must never write to the process's stderr; capture its text so errors can quote it.
        err_ = open_memstream(&buffer_, &bufferSize_);
        if (!err_) err_ = std::fopen("/dev/null", "w");
        if (!err_) fail(kDef, "cannot open a scratch stream for qhull");
        qh_zero(qh_.get(), err_);
    }
    ~QhullRun() {
        if (started_) {
            int curlong = 0, totlong = 0;
            qh_freeqhull(qh_.get(), !qh_ALL);
            qh_memfreeshort(qh_.get(), &curlong, &totlong);
        }
        if (err_) std::fclose(err_);
        std::free(buffer_);
    }
    QhullRun(const QhullRun&) = delete;
    QhullRun& operator=(const QhullRun&) = delete;

    int run(std::vector<double>& coords) {
        started_ = true;
        // "Qs" searches all points for the initial simplex: slower by one pass, but thin clouds stay solvable.
        char command[] = "qhull Qs";
        return qh_new_qhull(qh_.get(), 3, int(coords.size() / 3), coords.data(), False, command, nullptr, err_);
    }

    std::vector<RawFace> faces(const double* base) {
        qhT* qh = qh_.get();  // the FORALL/FOREACH macros name `qh`
        std::vector<RawFace> out;
        facetT* facet;
        vertexT *vertex, **vertexp;
        FORALLfacets {
            RawFace f;
            f.normal = {facet->normal[0], facet->normal[1], facet->normal[2]};
            FOREACHvertex_(facet->vertices) { f.points.push_back(std::uint32_t((vertex->point - base) / 3)); }
            out.push_back(std::move(f));
        }
        return out;
    }

    std::string firstErrorLine() {
        std::fflush(err_);
        if (!buffer_) return {};
        std::string text(buffer_, bufferSize_);
        const auto start = text.find("QH");
        if (start != std::string::npos) text.erase(0, start);
        return text.substr(0, text.find('\n'));
    }

private:
    std::unique_ptr<qhT> qh_;
    FILE* err_ = nullptr;
    char* buffer_ = nullptr;
    std::size_t bufferSize_ = 0;
    bool started_ = false;
};

// Orders a face's points counter-clockwise around its outward normal and drops points that are not corners
// (inside the polygon, or on an edge between two corners). The test is a distance against the hull's size, so a
// point on a shared edge is dropped from both faces alike.
std::vector<std::uint32_t> faceLoop(const std::vector<Vec3>& points, const RawFace& face, double tolerance) {
    D3 n = face.normal;
    const double nl = norm(n);
    n = {n.x / nl, n.y / nl, n.z / nl};
    const D3 helper = std::abs(n.x) < 0.6 ? D3{1, 0, 0} : D3{0, 1, 0};
    D3 u = cross(helper, n);
    const double ul = norm(u);
    u = {u.x / ul, u.y / ul, u.z / ul};
    const D3 v = cross(n, u);  // (u, v, n) right-handed: counter-clockwise in (u, v) is counter-clockwise from outside

    struct P2 {
        double x, y;
        std::uint32_t id;
    };
    std::vector<P2> p;
    for (std::uint32_t id : face.points) {
        const D3 q = toD3(points[id]);
        p.push_back({dot(q, u), dot(q, v), id});
    }
    std::sort(p.begin(), p.end(), [](const P2& a, const P2& b) { return a.x != b.x ? a.x < b.x : a.y < b.y; });
    if (p.size() < 3) return {};

    // Andrew's monotone chain; a middle point survives only if it lies left of its neighbours' line by more than
    // the tolerance.
    auto keeps = [&](const P2& o, const P2& a, const P2& b) {
        const double ex = b.x - o.x, ey = b.y - o.y;
        const double turn = (a.x - o.x) * ey - (a.y - o.y) * ex;  // > 0: o -> a -> b turns left
        return turn > tolerance * std::sqrt(ex * ex + ey * ey);
    };
    std::vector<P2> loop(2 * p.size());
    std::size_t k = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        while (k >= 2 && !keeps(loop[k - 2], loop[k - 1], p[i])) --k;
        loop[k++] = p[i];
    }
    for (std::size_t i = p.size() - 1, lower = k + 1; i-- > 0;) {
        while (k >= lower && !keeps(loop[k - 2], loop[k - 1], p[i])) --k;
        loop[k++] = p[i];
    }
    loop.resize(k - 1);  // the last point repeats the first
    std::vector<std::uint32_t> ids;
    for (const P2& q : loop) ids.push_back(q.id);
    if (ids.size() < 3) ids.clear();
    return ids;
}

}  // namespace

ConvexHull buildConvexHull(const std::vector<Vec3>& points) {
    if (points.size() < 4) fail(kDef, "needs at least 4 points (got " + std::to_string(points.size()) + ")");
    if (points.size() > std::size_t(INT_MAX / 3)) fail(kDef, "too many points (" + std::to_string(points.size()) + ")");
    for (std::size_t i = 0; i < points.size(); ++i)
        if (!isFinite(points[i])) fail(kDef, "points[" + std::to_string(i) + "] is not finite " + describe(points[i]));
    requireVolume(points);

    // Qhull's precision estimates are relative to the coordinates' magnitude, so hand it a centred cloud.
    D3 lo = toD3(points[0]), hi = lo;
    for (Vec3 p : points) {
        lo = {std::min(lo.x, double(p.x)), std::min(lo.y, double(p.y)), std::min(lo.z, double(p.z))};
        hi = {std::max(hi.x, double(p.x)), std::max(hi.y, double(p.y)), std::max(hi.z, double(p.z))};
    }
    const D3 centre{0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), 0.5 * (lo.z + hi.z)};
    const double size = norm(hi - lo);
    std::vector<double> coords(points.size() * 3);
    for (std::size_t i = 0; i < points.size(); ++i) {
        coords[3 * i + 0] = points[i].x - centre.x;
        coords[3 * i + 1] = points[i].y - centre.y;
        coords[3 * i + 2] = points[i].z - centre.z;
    }

    std::vector<RawFace> raw;
    {
        QhullRun qhull;
        const int code = qhull.run(coords);
        if (code == qh_ERRsingular)
            fail(kDef, "the " + std::to_string(points.size()) + " points are coplanar: a hull needs volume");
        if (code != qh_ERRnone) {
            const std::string detail = qhull.firstErrorLine();
            fail(kDef, "qhull failed (code " + std::to_string(code) + ")" + (detail.empty() ? "" : ": " + detail));
        }
        raw = qhull.faces(coords.data());
    }

    // Vertices keep their input order (deterministic and easy to relate to the definition) but only corners stay.
    const double tolerance = 1e-6 * size;
    std::vector<std::vector<std::uint32_t>> loops;
    std::vector<D3> normals;
    for (const RawFace& f : raw) {
        std::vector<std::uint32_t> loop = faceLoop(points, f, tolerance);
        if (loop.empty()) continue;  // a sliver facet with no area left once non-corners are dropped
        loops.push_back(std::move(loop));
        const double nl = norm(f.normal);
        normals.push_back({f.normal.x / nl, f.normal.y / nl, f.normal.z / nl});
    }
    if (loops.size() < 4)
        fail(kDef, "the " + std::to_string(points.size()) + " points are coplanar: a hull needs volume");

    std::vector<std::uint32_t> remap(points.size(), UINT32_MAX);
    for (const auto& loop : loops)
        for (std::uint32_t id : loop) remap[id] = 0;
    ConvexHull hull;
    for (std::uint32_t i = 0; i < points.size(); ++i) {
        if (remap[i] == UINT32_MAX) continue;
        remap[i] = std::uint32_t(hull.vertices.size());
        hull.vertices.push_back(points[i]);
    }

    std::vector<std::array<std::uint32_t, 2>> edges;
    for (std::size_t f = 0; f < loops.size(); ++f) {
        hull.faceStart.push_back(std::uint32_t(hull.faceVertices.size()));
        double offset = -HUGE_VAL;
        const auto& loop = loops[f];
        for (std::size_t k = 0; k < loop.size(); ++k) {
            const std::uint32_t a = remap[loop[k]], b = remap[loop[(k + 1) % loop.size()]];
            hull.faceVertices.push_back(a);
            edges.push_back({std::min(a, b), std::max(a, b)});
            // The plane passes through the outermost corner so that every vertex is on or inside it.
            offset = std::max(offset, dot(normals[f], toD3(points[loop[k]])));
        }
        hull.faceNormals.push_back({float(normals[f].x), float(normals[f].y), float(normals[f].z)});
        hull.faceOffsets.push_back(float(offset));
    }
    hull.faceStart.push_back(std::uint32_t(hull.faceVertices.size()));
    std::sort(edges.begin(), edges.end());
    edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
    for (const auto& e : edges) {
        hull.edges.push_back(e[0]);
        hull.edges.push_back(e[1]);
    }
    return hull;
}

}  // namespace rubble::detail
