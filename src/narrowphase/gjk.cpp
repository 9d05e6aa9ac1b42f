// GJK distance. The iteration runs in double precision relative to A's position: the simplex sub-problems divide by
// areas and volumes that lose all their bits in float once the shapes are far from the origin or nearly degenerate,
// and the cost is in the support mappings, not in the arithmetic.
//
// The sub-algorithm is the Voronoi-region search of Ericson (5.1.2, 5.1.5, 5.1.6): the closest point of the
// simplex to the origin, with its barycentric coordinates, keeping only the vertices that support it.
#include "narrowphase/gjk.h"

#include <cmath>

#include "shapes/shape.h"

namespace rubble::detail {
namespace {

struct V3 {
    double x = 0, y = 0, z = 0;
};
V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3 operator-(V3 a) { return {-a.x, -a.y, -a.z}; }
V3 operator*(V3 a, double s) { return {a.x * s, a.y * s, a.z * s}; }
double dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
V3 toD(Vec3 v) { return {v.x, v.y, v.z}; }
Vec3 toF(V3 v) { return {static_cast<float>(v.x), static_cast<float>(v.y), static_cast<float>(v.z)}; }

struct Q4 {
    double x = 0, y = 0, z = 0, w = 1;
};
V3 rotate(Q4 q, V3 v) {
    const V3 u{q.x, q.y, q.z};
    const V3 t = cross(u, v) * 2.0;
    return v + t * q.w + cross(u, t);
}
V3 rotateInverse(Q4 q, V3 v) { return rotate({-q.x, -q.y, -q.z, q.w}, v); }

/// A shape prepared for the iteration: double rotation, position relative to the reference point.
struct Prepared {
    const GjkShape* shape;
    Q4 rotation;
    V3 position;
};

Prepared prepare(const GjkShape& s, Vec3 origin) {
    const Quat& q = s.pose.rotation;
    // Normalise in double so a float quaternion that is unit to 1e-7 rotates without stretching.
    const double len = std::sqrt(double(q.x) * q.x + double(q.y) * q.y + double(q.z) * q.z + double(q.w) * q.w);
    const double inv = len > 0 ? 1.0 / len : 1.0;
    return {&s, {q.x * inv, q.y * inv, q.z * inv, len > 0 ? q.w * inv : 1.0}, toD(s.pose.position) - toD(origin)};
}

double sgn(double v) { return v < 0 ? -1.0 : 1.0; }

V3 localSupport(const GjkShape& s, V3 d) {
    switch (s.core) {
        case GjkShape::Core::Point:
            return {};
        case GjkShape::Core::Segment:
            return {0, sgn(d.y) * s.halfHeight, 0};
        case GjkShape::Core::Box:
            return {sgn(d.x) * s.halfExtents.x, sgn(d.y) * s.halfExtents.y, sgn(d.z) * s.halfExtents.z};
        case GjkShape::Core::Points: {
            if (s.pointCount == 0) return {};
            std::uint32_t best = 0;
            double bestDot = dot(toD(s.points[0]), d);
            for (std::uint32_t i = 1; i < s.pointCount; ++i) {
                const double p = dot(toD(s.points[i]), d);
                if (p > bestDot) bestDot = p, best = i;
            }
            return toD(s.points[best]);
        }
    }
    return {};
}

V3 support(const Prepared& p, V3 d) {
    return rotate(p.rotation, localSupport(*p.shape, rotateInverse(p.rotation, d))) + p.position;
}

struct SimplexVertex {
    V3 a, b, w;  // support of A, support of B, w = a - b
};

struct Simplex {
    SimplexVertex v[4];
    double lambda[4] = {};
    int count = 0;
};

/// Keeps the vertices listed in `keep` with their barycentric weights.
void reduce(Simplex& s, std::initializer_list<int> keep, std::initializer_list<double> weights) {
    SimplexVertex nv[4];
    double nl[4];
    int n = 0;
    auto w = weights.begin();
    for (int k : keep) {
        nv[n] = s.v[k];
        nl[n] = *w++;
        ++n;
    }
    for (int i = 0; i < n; ++i) s.v[i] = nv[i], s.lambda[i] = nl[i];
    s.count = n;
}

/// Closest point of segment (0, 1) of the simplex to the origin (Ericson 5.1.2).
void solveSegment(Simplex& s) {
    const V3 a = s.v[0].w, b = s.v[1].w;
    const V3 ab = b - a;
    const double t = -dot(a, ab);
    if (t <= 0) return reduce(s, {0}, {1.0});
    const double denom = dot(ab, ab);
    if (t >= denom) return reduce(s, {1}, {1.0});
    const double u = t / denom;
    reduce(s, {0, 1}, {1 - u, u});
}

/// Closest point of the triangle (i, j, k) of the simplex to the origin (Ericson 5.1.5 with p = 0). Returns the
/// squared distance and writes the reduced simplex into `out`.
double solveTriangle(const Simplex& s, int i, int j, int k, Simplex& out) {
    out = s;
    const V3 a = s.v[i].w, b = s.v[j].w, c = s.v[k].w;
    const V3 ab = b - a, ac = c - a;
    auto finish = [&](std::initializer_list<int> keep, std::initializer_list<double> weights) {
        reduce(out, keep, weights);
        V3 p{};
        for (int m = 0; m < out.count; ++m) p = p + out.v[m].w * out.lambda[m];
        return dot(p, p);
    };
    const double d1 = -dot(ab, a), d2 = -dot(ac, a);
    if (d1 <= 0 && d2 <= 0) return finish({i}, {1.0});
    const double d3 = -dot(ab, b), d4 = -dot(ac, b);
    if (d3 >= 0 && d4 <= d3) return finish({j}, {1.0});
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        return finish({i, j}, {1 - v, v});
    }
    const double d5 = -dot(ab, c), d6 = -dot(ac, c);
    if (d6 >= 0 && d5 <= d6) return finish({k}, {1.0});
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        return finish({i, k}, {1 - w, w});
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return finish({j, k}, {1 - w, w});
    }
    const double denom = va + vb + vc;
    if (!(denom > 0)) {  // degenerate (collinear) triangle: best of its edges
        Simplex best, trial;
        double bestD = INFINITY;
        const int edges[3][2] = {{i, j}, {i, k}, {j, k}};
        for (const auto& e : edges) {
            trial = s;
            reduce(trial, {e[0], e[1]}, {0.0, 0.0});
            solveSegment(trial);
            V3 p{};
            for (int m = 0; m < trial.count; ++m) p = p + trial.v[m].w * trial.lambda[m];
            if (dot(p, p) < bestD) bestD = dot(p, p), best = trial;
        }
        out = best;
        return bestD;
    }
    const double v = vb / denom, w = vc / denom;
    return finish({i, j, k}, {1 - v - w, v, w});
}

/// Closest point of the tetrahedron to the origin (Ericson 5.1.6). Returns false when the origin is inside.
bool solveTetrahedron(Simplex& s) {
    const V3 a = s.v[0].w, b = s.v[1].w, c = s.v[2].w, d = s.v[3].w;
    const double volume = dot(b - a, cross(c - a, d - a));
    const double scale = std::sqrt(dot(b - a, b - a) * dot(c - a, c - a) * dot(d - a, d - a));
    const bool degenerate = !(std::fabs(volume) > 1e-12 * scale);
    // Face (i, j, k) with the opposite vertex l: the origin is outside when it lies across the face's plane.
    const int faces[4][4] = {{0, 1, 2, 3}, {0, 2, 3, 1}, {0, 3, 1, 2}, {1, 3, 2, 0}};
    double bestD = INFINITY;
    Simplex best, trial;
    bool anyOutside = false;
    for (const auto& f : faces) {
        const V3 p = s.v[f[0]].w;
        const V3 n = cross(s.v[f[1]].w - p, s.v[f[2]].w - p);
        const double sideOrigin = -dot(p, n);
        const double sideOther = dot(s.v[f[3]].w - p, n);
        if (!degenerate && !(sideOrigin * sideOther < 0)) continue;
        anyOutside = true;
        const double dist = solveTriangle(s, f[0], f[1], f[2], trial);
        if (dist < bestD) bestD = dist, best = trial;
    }
    if (!anyOutside) return false;
    s = best;
    return true;
}

V3 closestPoint(const Simplex& s) {
    V3 p{};
    for (int i = 0; i < s.count; ++i) p = p + s.v[i].w * s.lambda[i];
    return p;
}

}  // namespace

GjkShape gjkShapeOf(const Shape& shape, const Transform& pose) {
    GjkShape g;
    g.pose = pose;
    switch (shape.kind) {
        case ShapeKind::Sphere:
            g.core = GjkShape::Core::Point;
            g.radius = shape.radius;
            break;
        case ShapeKind::Capsule:
            g.core = GjkShape::Core::Segment;
            g.radius = shape.radius;
            g.halfHeight = shape.halfHeight;
            break;
        case ShapeKind::Box:
            g.core = GjkShape::Core::Box;
            g.halfExtents = shape.halfExtents;
            break;
        case ShapeKind::ConvexHull:
            if (shape.hull) {
                g.core = GjkShape::Core::Points;
                g.points = shape.hull->vertices.data();
                g.pointCount = static_cast<std::uint32_t>(shape.hull->vertices.size());
            }
            break;
        default:
            break;
    }
    return g;
}

Vec3 gjkSupport(const GjkShape& s, Vec3 d) {
    const Prepared p = prepare(s, {});
    return toF(support(p, toD(d)));
}

GjkResult gjkDistance(const GjkShape& shapeA, const GjkShape& shapeB, const GjkSettings& settings) {
    const Vec3 origin = shapeA.pose.position;
    const Prepared pa = prepare(shapeA, origin), pb = prepare(shapeB, origin);
    GjkResult result;

    // v: current closest point of A - B to the origin (so -v points from A towards B).
    V3 v = -toD(settings.initialDirection);
    if (dot(v, v) == 0) v = pa.position - pb.position;
    if (dot(v, v) == 0) v = {1, 0, 0};

    Simplex simplex;
    const double relTol2 = double(settings.relativeTolerance) * settings.relativeTolerance;
    const double absTol = settings.absoluteTolerance;
    double vv = INFINITY;
    bool overlap = false;
    int iter = 0;
    for (; iter < settings.maxIterations; ++iter) {
        SimplexVertex nv;
        nv.a = support(pa, -v);
        nv.b = support(pb, v);
        nv.w = nv.a - nv.b;
        if (simplex.count > 0) {
            // Lower-bound test (van den Bergen): |v|^2 - v.w is how much the distance can still shrink.
            const double gap = vv - dot(v, nv.w);
            if (gap <= relTol2 * vv) break;
            bool repeated = false;  // a repeated support point means no progress is possible
            for (int i = 0; i < simplex.count; ++i) {
                const V3 e = simplex.v[i].w - nv.w;
                if (dot(e, e) <= 1e-24 * (1 + vv)) repeated = true;
            }
            if (repeated) break;
        }
        const Simplex previous = simplex;
        simplex.v[simplex.count] = nv;
        simplex.lambda[simplex.count] = 0;
        ++simplex.count;
        switch (simplex.count) {
            case 1:
                simplex.lambda[0] = 1;
                break;
            case 2:
                solveSegment(simplex);
                break;
            case 3: {
                Simplex out;
                solveTriangle(simplex, 0, 1, 2, out);
                simplex = out;
                break;
            }
            default:
                if (!solveTetrahedron(simplex)) overlap = true;
                break;
        }
        if (overlap) break;
        const V3 nvPoint = closestPoint(simplex);
        const double nvv = dot(nvPoint, nvPoint);
        if (nvv >= vv) {  // no progress (rounding): keep the previous, better simplex
            simplex = previous;
            break;
        }
        v = nvPoint;
        vv = nvv;
        if (vv <= absTol * absTol) {
            overlap = true;
            break;
        }
    }
    result.iterations = iter;
    if (overlap || simplex.count == 0) {
        result.status = GjkStatus::CoresOverlap;
        return result;
    }

    V3 pA{}, pB{};
    for (int i = 0; i < simplex.count; ++i) {
        pA = pA + simplex.v[i].a * simplex.lambda[i];
        pB = pB + simplex.v[i].b * simplex.lambda[i];
    }
    const V3 d = pB - pA;
    const double coreDistance = std::sqrt(dot(d, d));
    if (!(coreDistance > absTol)) {
        result.status = GjkStatus::CoresOverlap;
        return result;
    }
    const V3 n = d * (1.0 / coreDistance);
    pA = pA + n * double(shapeA.radius);
    pB = pB - n * double(shapeB.radius);
    const double distance = coreDistance - shapeA.radius - shapeB.radius;
    const V3 o = toD(origin);
    result.status = distance > 0 ? GjkStatus::Separated : GjkStatus::RadiiOverlap;
    result.distance = static_cast<float>(distance);
    result.pointA = toF(pA + o);
    result.pointB = toF(pB + o);
    result.normal = toF(n);
    return result;
}

}  // namespace rubble::detail
