#pragma once
// A vertical sheet of kSide x kSide spheres of 1 kg, 1 m apart, each ball-jointed to its right and lower neighbours at
// the midpoints, hung from its static top row (Box3D's joint_grid, smaller): 870 joints down the columns and 841
// across the rows, one island, at the default settings (soft step), awake throughout. Enough joints for the joint
// solver to colour them and run their ball joints in SIMD lanes (src/solver/joint_solver.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include "rubble/world.h"

namespace rubble::test {

struct Sheet {
    static constexpr int kSide = 30;
    World world;
    std::vector<BodyId> nodes;  ///< by place, row by row from the top
    std::vector<JointId> down;  ///< column joints: down[(row - 1) * kSide + col] joins row - 1 and row
    std::vector<JointId> across;
    std::vector<JointId> braces;

    /// `scattered`: the spheres and their joints are created in a shuffled order (the solver's body rows then follow
    /// no place). `braced`: each sphere is also jointed to its mirror image across the sheet's middle column, at the
    /// midpoint between them, so that a fifth of the joints cross any cut down the middle.
    explicit Sheet(int threads, bool scattered = false, bool braced = false)
        : world([threads] {
              WorldSettings s;
              s.threads = threads;
              s.effects = s.effects.without(Effect::Sleeping);
              return s;
          }()),
          nodes(std::size_t(kSide * kSide)) {
        std::vector<int> order(std::size_t(kSide * kSide));
        for (std::size_t k = 0; k < order.size(); ++k) order[k] = int(k);
        if (scattered) {
            std::uint32_t random = 12345;
            for (std::size_t k = order.size() - 1; k > 0; --k) {
                random = random * 1664525u + 1013904223u;
                std::swap(order[k], order[(random >> 8) % (k + 1)]);
            }
        }
        for (const int k : order) {
            const int row = k / kSide, col = k % kSide;
            BodyDef def;
            def.type = row == 0 ? BodyType::Static : BodyType::Dynamic;
            def.shape = world.createShape(SphereDef{0.4f});
            def.position = {float(col), -float(row), 0};
            def.material.density = 1.0f / (4.0f / 3.0f * 3.14159265f * 0.4f * 0.4f * 0.4f);
            def.material.friction = 0;
            nodes[std::size_t(k)] = world.createBody(def);
        }
        // Each sphere's joints up and to the left, in the same order: the solver numbers the rows of bodies in no
        // contact in the order the joints name them.
        down.resize(std::size_t((kSide - 1) * kSide));
        across.resize(std::size_t((kSide - 1) * (kSide - 1)));
        for (const int k : order) {
            const int row = k / kSide, col = k % kSide;
            if (row == 0) continue;
            BallJointDef ball;
            ball.bodyA = node(row - 1, col);
            ball.bodyB = node(row, col);
            ball.localAnchorA = {0, -0.5f, 0};
            ball.localAnchorB = {0, 0.5f, 0};
            down[std::size_t((row - 1) * kSide + col)] = world.createJoint(ball);
            if (col > 0) {
                ball.bodyA = node(row, col - 1);
                ball.localAnchorA = {0.5f, 0, 0};
                ball.localAnchorB = {-0.5f, 0, 0};
                across[std::size_t((row - 1) * (kSide - 1) + col - 1)] = world.createJoint(ball);
            }
            const int mirror = kSide - 1 - col;
            if (braced && col < mirror) {
                const float half = 0.5f * float(mirror - col);
                ball.bodyA = node(row, col);
                ball.bodyB = node(row, mirror);
                ball.localAnchorA = {half, 0, 0};
                ball.localAnchorB = {-half, 0, 0};
                braces.push_back(world.createJoint(ball));
            }
        }
    }
    BodyId node(int row, int col) const { return nodes[std::size_t(row * kSide + col)]; }
    /// The largest change of length between neighbours.
    float stretch() const {
        float worst = 0;
        for (const std::vector<JointId>* joints : {&down, &across})
            for (const JointId j : *joints) {
                const auto [a, b] = world.jointBodies(j);
                const Vec3 pa = world.transform(a).position, pb = world.transform(b).position;
                worst = std::max(worst, std::fabs(length(pb - pa) - 1.0f));
            }
        return worst;
    }
};

}  // namespace rubble::test
