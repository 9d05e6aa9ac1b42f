// The marble demo: the maze can be solved, its floor faces up and is continuous, and the ball, steered only by the
// autopilot's forces (through the runtime's input queue, as the viewer does), rolls from the start to the goal
// without leaving the maze, falling through it or hopping over its floor's edges.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "marble_demo.h"
#include "rubble/runtime.h"
#include "rubble/world.h"

using namespace rubble;
using namespace rubble::viewer;

TEST(MarbleMaze, PathRunsThroughOpenNeighbouringCellsFromStartToGoal) {
    const MarbleMaze maze = MarbleMaze::standard();
    const std::vector<Vec3> path = maze.solve();
    ASSERT_GE(path.size(), 2u);
    int r = 0, c = 0;
    maze.find('S', r, c);
    EXPECT_EQ(path.front(), maze.cellCenter(r, c));
    maze.find('G', r, c);
    EXPECT_EQ(path.back(), maze.cellCenter(r, c));
    for (std::size_t i = 1; i < path.size(); ++i) {
        const float step = std::hypot(path[i].x - path[i - 1].x, path[i].z - path[i - 1].z);
        EXPECT_NEAR(step, MarbleMaze::kCellSize, 1e-4f)
            << "waypoints " << i - 1 << " and " << i << " are not neighbours";
    }
}

TEST(MarbleMaze, FloorFacesUpAndEveryOpenCellHasIt) {
    const MarbleMaze maze = MarbleMaze::standard();
    const TriangleMeshDef floor = maze.buildFloor();
    int open = 0;
    for (int r = 0; r < maze.rows(); ++r)
        for (int c = 0; c < maze.columns(); ++c) open += maze.isWall(r, c) ? 0 : 1;
    ASSERT_EQ(floor.indices.size(), 6u * open);
    for (std::size_t t = 0; t < floor.indices.size(); t += 3) {
        const Vec3 a = floor.vertices[floor.indices[t]], b = floor.vertices[floor.indices[t + 1]],
                   c = floor.vertices[floor.indices[t + 2]];
        EXPECT_GT(cross(b - a, c - a).y, 0);
    }
    // Walls face away from their cells: every wall triangle's normal is up or horizontal.
    const TriangleMeshDef walls = maze.buildWalls();
    EXPECT_GT(walls.indices.size(), 0u);
    for (std::size_t t = 0; t < walls.indices.size(); t += 3) {
        const Vec3 a = walls.vertices[walls.indices[t]], b = walls.vertices[walls.indices[t + 1]],
                   c = walls.vertices[walls.indices[t + 2]];
        EXPECT_GE(cross(b - a, c - a).y, -1e-5f);
    }
}

TEST(MarbleDemo, AutopilotRollsTheBallToTheGoal) {
    World world = MarbleDemo::makeWorld();
    MarbleDemo demo;
    demo.build(world);
    const float floorY = 0;
    Runtime runtime(std::move(world));
    VelocityEstimate velocity;
    const double frame = 1.0 / 60;
    bool reached = false;
    double lowest = 1e9, highestOnFlat = -1e9;
    int frames = 0;
    // The path is about 60 cells of 2.5 m at a cruise of 2.5 m/s: a minute; two are allowed.
    for (; frames < 120 * 60 && !reached; ++frames) {
        const RenderFrame& f = runtime.latest(1);
        if (f.slotCount() > demo.ball.index) {
            const Vec3 p{f.px[demo.ball.index], f.py[demo.ball.index], f.pz[demo.ball.index]};
            velocity.update(p, f.time);
            lowest = std::min(lowest, static_cast<double>(p.y));
            // Past the ramp the floor is flat (y = 0), two triangles a cell: the ball's centre stays one radius up.
            // Half a cell past the ramp's foot, where a ball resting on both the ramp and the floor (its centre
            // radius / cos(slope) up) has rolled on.
            const float row = p.z / MarbleMaze::kCellSize + 0.5f * static_cast<float>(demo.maze.rows());
            if (row >= static_cast<float>(MarbleMaze::kRampRows) + 0.5f)
                highestOnFlat = std::max(highestOnFlat, static_cast<double>(p.y));
            reached = demo.atGoal(p);
            runtime.submit(ApplyImpulseCommand{demo.ball, demo.autopilotForce(p, velocity.velocity) * frame});
        }
        runtime.advance(frame);
    }
    EXPECT_TRUE(reached) << "after " << frames / 60.0 << " s the ball had not reached the goal (waypoint "
                         << demo.nextWaypoint << " of " << demo.path.size() << ")";
    // And it did roll there: the path is (cells - 1) cell sizes long, and the ball is no faster than 6 m/s.
    const double pathLength = static_cast<double>(demo.path.size() - 1) * MarbleMaze::kCellSize;
    EXPECT_GT(frames / 60.0, pathLength / 6.0);
    std::printf("the ball reached the goal after %.1f s over a %.0f m path\n", frames / 60.0, pathLength);
    // Never sank into the floor by more than the contact slop allows (the ball's centre is one radius above it).
    EXPECT_GT(lowest, floorY + MarbleDemo::kBallRadius - 0.05);
    // And never hopped over the flat floor's internal edges (a ghost bump at 1 m/s lifts the ball 5 cm; the ball
    // rolls at up to 6 m/s): 1 cm covers the soft contact's give and the frames' interpolation.
    EXPECT_LT(highestOnFlat, floorY + MarbleDemo::kBallRadius + 0.01);
}

TEST(MarbleDemo, ArrowsPushAlongTheCameraGroundPlane) {
    World world = MarbleDemo::makeWorld();
    MarbleDemo demo;
    demo.build(world);
    const Vec3 forward = demo.steeringForce(0, 1, {0, -0.7f, -0.7f});
    EXPECT_NEAR(forward.y, 0, 1e-6f);
    EXPECT_LT(forward.z, 0);
    EXPECT_NEAR(length(forward), MarbleDemo::kSteerAcceleration * demo.ballMass, 1e-3f * demo.ballMass);
    const Vec3 right = demo.steeringForce(1, 0, {0, -0.7f, -0.7f});
    EXPECT_GT(right.x, 0);  // looking along -z, the right is +x
    // Diagonals are no stronger than straight pushes.
    EXPECT_NEAR(length(demo.steeringForce(1, 1, {0, 0, -1})), length(forward), 1e-3f * demo.ballMass);
}
