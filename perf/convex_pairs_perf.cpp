// Narrow-phase kernel micro-benchmarks, one core: closed-form pair kernels batched in SIMD lanes against the scalar
// instantiation of the same kernels (items_per_second = pairs), and GJK distance queries for box-box and hull-hull
// (items_per_second = queries). The scalar form is an honest plain loop: the same kernel, fully inlined like the
// wide one, with GCC's auto-vectoriser off for the whole file (convex_pairs.cpp says why), so that it is not a second
// SIMD path in disguise. Box-box (scalar, batched) is in box_box_perf.cpp.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "narrowphase/convex_pairs.h"
#include "narrowphase/gjk.h"
#include "shapes/shape.h"

namespace {

using namespace rubble;
using namespace rubble::detail;

/// Pairs per batch: 512 keeps inputs and outputs (68 bytes a pair for sphere-sphere, 35 KB) in L1 and L2, so the
/// kernels are measured, not memory (BM_SphereSphereStreamed shows the other end).
constexpr std::size_t kPairs = 512;
constexpr float kMargin = 0.05f;

std::vector<float> randomArray(std::mt19937& rng, float lo, float hi) {
    std::uniform_real_distribution<float> u(lo, hi);
    std::vector<float> v(kPairs);
    for (float& x : v) x = u(rng);
    return v;
}

/// Random inputs for every kernel (centres in a 2 m cube, sizes 0.1 .. 0.6 m: about half the pairs touch) and
/// output arrays.
struct Data {
    std::mt19937 rng{42};
    std::vector<float> ax = randomArray(rng, -1, 1), ay = randomArray(rng, -1, 1), az = randomArray(rng, -1, 1);
    std::vector<float> bx = randomArray(rng, -1, 1), by = randomArray(rng, -1, 1), bz = randomArray(rng, -1, 1);
    std::vector<float> ar = randomArray(rng, 0.1f, 0.6f), br = randomArray(rng, 0.1f, 0.6f);
    std::vector<float> ahx = randomArray(rng, -0.5f, 0.5f), ahy = randomArray(rng, -0.5f, 0.5f),
                       ahz = randomArray(rng, -0.5f, 0.5f);
    std::vector<float> bhx = randomArray(rng, -0.5f, 0.5f), bhy = randomArray(rng, -0.5f, 0.5f),
                       bhz = randomArray(rng, -0.5f, 0.5f);
    std::vector<float> qx, qy, qz, qw;
    std::vector<float> ex = randomArray(rng, 0.1f, 0.6f), ey = randomArray(rng, 0.1f, 0.6f),
                       ez = randomArray(rng, 0.1f, 0.6f);
    std::vector<float> nx = std::vector<float>(kPairs), ny = nx, nz = nx, px = nx, py = nx, pz = nx, depth = nx,
                       qpx = nx, qpy = nx, qpz = nx, depth1 = nx;
    std::vector<std::uint32_t> feature = std::vector<std::uint32_t>(kPairs), feature1 = feature;
    std::vector<std::int32_t> count = std::vector<std::int32_t>(kPairs);

    Data() {
        std::normal_distribution<float> n(0, 1);
        for (std::size_t i = 0; i < kPairs; ++i) {
            float q[4] = {n(rng), n(rng), n(rng), n(rng)};
            const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            qx.push_back(q[0] / len), qy.push_back(q[1] / len), qz.push_back(q[2] / len), qw.push_back(q[3] / len);
        }
    }
    PairContacts out() {
        return {nx.data(),      ny.data(),    nz.data(),  px.data(),  py.data(),  pz.data(),     depth.data(),
                feature.data(), count.data(), qpx.data(), qpy.data(), qpz.data(), depth1.data(), feature1.data()};
    }
};

template <class Run>
void runPairs(benchmark::State& state, Data& d, Run&& run) {
    for (auto _ : state) {
        run();
        benchmark::DoNotOptimize(d.depth.data());
        benchmark::ClobberMemory();
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * kPairs));
}

/// state.range(0): 1 = batched SIMD, 0 = scalar.
void BM_SphereSphere(benchmark::State& state) {
    Data d;
    const SpherePairs in{d.ax.data(), d.ay.data(), d.az.data(), d.ar.data(),
                         d.bx.data(), d.by.data(), d.bz.data(), d.br.data()};
    const PairContacts out = d.out();
    const bool wide = state.range(0) != 0;
    runPairs(state, d, [&] {
        wide ? collideSpheresBatch(in, kPairs, kMargin, out) : collideSpheresBatchScalar(in, kPairs, kMargin, out);
    });
}

void BM_SphereCapsule(benchmark::State& state) {
    Data d;
    const SphereCapsulePairs in{d.ax.data(), d.ay.data(),  d.az.data(),  d.ar.data(),  d.bx.data(), d.by.data(),
                                d.bz.data(), d.bhx.data(), d.bhy.data(), d.bhz.data(), d.br.data()};
    const PairContacts out = d.out();
    const bool wide = state.range(0) != 0;
    runPairs(state, d, [&] {
        wide ? collideSphereCapsulesBatch(in, kPairs, kMargin, out)
             : collideSphereCapsulesBatchScalar(in, kPairs, kMargin, out);
    });
}

void BM_CapsuleCapsule(benchmark::State& state) {
    Data d;
    const CapsulePairs in{d.ax.data(), d.ay.data(), d.az.data(), d.ahx.data(), d.ahy.data(), d.ahz.data(), d.ar.data(),
                          d.bx.data(), d.by.data(), d.bz.data(), d.bhx.data(), d.bhy.data(), d.bhz.data(), d.br.data()};
    const PairContacts out = d.out();
    const bool wide = state.range(0) != 0;
    runPairs(state, d, [&] {
        wide ? collideCapsulesBatch(in, kPairs, kMargin, out) : collideCapsulesBatchScalar(in, kPairs, kMargin, out);
    });
}

void BM_SphereBox(benchmark::State& state) {
    Data d;
    const SphereBoxPairs in{d.ax.data(), d.ay.data(), d.az.data(), d.ar.data(), d.bx.data(), d.by.data(), d.bz.data(),
                            d.qx.data(), d.qy.data(), d.qz.data(), d.qw.data(), d.ex.data(), d.ey.data(), d.ez.data()};
    const PairContacts out = d.out();
    const bool wide = state.range(0) != 0;
    runPairs(state, d, [&] {
        wide ? collideSphereBoxesBatch(in, kPairs, kMargin, out)
             : collideSphereBoxesBatchScalar(in, kPairs, kMargin, out);
    });
}

BENCHMARK(BM_SphereSphere)->Arg(0)->Arg(1)->ArgName("simd");

/// Sphere-sphere over 2^20 pairs (72 MB of inputs and outputs, far beyond the caches): what the kernel does when
/// every byte comes from and goes to memory. Each pair reads 8 floats (32 bytes) and writes 7 floats, a feature
/// and a count (36 bytes); bytes_per_second counts those 68 bytes a pair, so it shows how close the batched kernel
/// gets to the machine's memory bandwidth (the ceiling for streamed pairs, whichever form computes them).
void BM_SphereSphereStreamed(benchmark::State& state) {
    constexpr std::size_t kStreamed = std::size_t{1} << 20;
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> pos(-1, 1), radius(0.1f, 0.6f);
    std::vector<float> in[8], out[7];
    for (int k = 0; k < 8; ++k) {
        in[k].resize(kStreamed);
        for (float& x : in[k]) x = (k == 3 || k == 7) ? radius(rng) : pos(rng);
    }
    for (auto& o : out) o.resize(kStreamed);
    std::vector<std::uint32_t> feature(kStreamed);
    std::vector<std::int32_t> count(kStreamed);
    const SpherePairs pairs{in[0].data(), in[1].data(), in[2].data(), in[3].data(),
                            in[4].data(), in[5].data(), in[6].data(), in[7].data()};
    const PairContacts result{out[0].data(), out[1].data(), out[2].data(),  out[3].data(), out[4].data(),
                              out[5].data(), out[6].data(), feature.data(), count.data()};
    const bool wide = state.range(0) != 0;
    for (auto _ : state) {
        wide ? collideSpheresBatch(pairs, kStreamed, kMargin, result)
             : collideSpheresBatchScalar(pairs, kStreamed, kMargin, result);
        benchmark::DoNotOptimize(count.data());
        benchmark::ClobberMemory();
    }
    const auto items = static_cast<std::int64_t>(state.iterations() * kStreamed);
    state.SetItemsProcessed(items);
    state.SetBytesProcessed(items * 68);
}
BENCHMARK(BM_SphereSphereStreamed)->Arg(0)->Arg(1)->ArgName("simd")->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SphereCapsule)->Arg(0)->Arg(1)->ArgName("simd");
BENCHMARK(BM_CapsuleCapsule)->Arg(0)->Arg(1)->ArgName("simd");
BENCHMARK(BM_SphereBox)->Arg(0)->Arg(1)->ArgName("simd");

/// GJK distance queries over 256 random pairs (about half separated). range(0): 0 = box-box, 1 = hull-hull
/// (hulls of 24 random points).
void BM_GjkDistance(benchmark::State& state) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1, 1), s(0.2f, 0.6f);
    std::normal_distribution<float> n(0, 1);
    std::vector<ConvexHull> hulls;
    std::vector<GjkShape> shapes;
    constexpr int kShapes = 512;
    hulls.reserve(kShapes);
    for (int i = 0; i < kShapes; ++i) {
        GjkShape g;
        float q[4] = {n(rng), n(rng), n(rng), n(rng)};
        const float len = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        g.pose = {{1.5f * u(rng), 1.5f * u(rng), 1.5f * u(rng)}, {q[0] / len, q[1] / len, q[2] / len, q[3] / len}};
        if (state.range(0) == 0) {
            g.core = GjkShape::Core::Box;
            g.halfExtents = {s(rng), s(rng), s(rng)};
        } else {
            std::vector<Vec3> pts;
            for (int k = 0; k < 24; ++k) pts.push_back(Vec3{u(rng), u(rng), u(rng)} * 0.5f);
            hulls.push_back(buildConvexHull(pts));
            g.core = GjkShape::Core::Points;
            g.points = hulls.back().vertices.data();
            g.pointCount = static_cast<std::uint32_t>(hulls.back().vertices.size());
        }
        shapes.push_back(g);
    }
    for (auto _ : state) {
        for (int i = 0; i < kShapes; i += 2) benchmark::DoNotOptimize(gjkDistance(shapes[i], shapes[i + 1]));
    }
    state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * (kShapes / 2)));
}
BENCHMARK(BM_GjkDistance)->Arg(0)->Arg(1)->ArgName("hull");

}  // namespace
