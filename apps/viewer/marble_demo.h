#pragma once
// The marble demo (after Marble Madness): a ball steered by forces through a maze that is one static triangle mesh,
// a floor whose first rows slope down from the start, and walls. Built without OpenGL so tests can run it.
#include <string>
#include <vector>

#include "rubble/id.h"
#include "rubble/math.h"
#include "rubble/shapes.h"

namespace rubble {
class World;
}

namespace rubble::viewer {

/// The maze: a grid of cells ('#' wall, '.' floor, 'S' start, 'G' goal), row 0 at -z, column 0 at -x.
struct MarbleMaze {
    static constexpr float kCellSize = 2.5f;    ///< m
    static constexpr float kWallHeight = 1.2f;  ///< m above the floor
    static constexpr float kRampDrop = 3.0f;    ///< m from the top corner row to the flat part
    static constexpr int kRampRows = 5;         ///< corner rows the floor slopes over

    std::vector<std::string> layout;

    /// The demo's maze.
    static MarbleMaze standard();

    int rows() const { return static_cast<int>(layout.size()); }
    int columns() const { return static_cast<int>(layout.front().size()); }
    bool isWall(int row, int column) const;
    /// Floor height at a cell corner (0 <= row <= rows(), 0 <= column <= columns()).
    float cornerHeight(int row, int column) const;
    /// Centre of a cell on its floor.
    Vec3 cellCenter(int row, int column) const;
    /// Cell of the first 'S' or 'G'.
    void find(char what, int& row, int& column) const;
    /// The floor of the open cells, counter-clockwise seen from above.
    TriangleMeshDef buildFloor() const;
    /// Wall tops and the wall sides that face a floor or the outside, counter-clockwise seen from outside.
    TriangleMeshDef buildWalls() const;
    /// Cell centres of a shortest path from 'S' to 'G' (breadth-first), both included; empty when there is none.
    std::vector<Vec3> solve() const;
};

/// The demo's world and the ball's steering.
struct MarbleDemo {
    static constexpr float kBallRadius = 0.45f;  ///< m
    /// Steering acceleration the arrows ask for, m/s^2 (the force is this times the ball's mass).
    static constexpr float kSteerAcceleration = 7.0f;

    MarbleMaze maze = MarbleMaze::standard();
    BodyId ball, beacon, floorBody, wallBody;
    float ballMass = 0;
    std::vector<Vec3> path;  ///< the autopilot's waypoints
    std::size_t nextWaypoint = 1;

    /// Creates the maze (floor and walls, two static meshes), the ball at the start and a beacon over the goal (it
    /// collides with nothing) in `world`.
    void build(World& world);
    /// Force for arrow input (right, forward in [-1, 1]) relative to a camera looking along `cameraForward`, in the
    /// ground plane.
    Vec3 steeringForce(float right, float forward, Vec3 cameraForward) const;
    /// Force with which the autopilot follows `path`, from the ball's position and velocity.
    Vec3 autopilotForce(Vec3 position, Vec3 velocity);
    /// True when the ball's centre is over the goal cell.
    bool atGoal(Vec3 position) const;
    /// A world for the demo: gravity, rotation and friction; one thread (one ball needs no more).
    static World makeWorld();
};

/// Velocity by finite differences of positions at simulated times (what the render side sees of a body).
struct VelocityEstimate {
    Vec3 velocity;
    bool valid = false;
    void update(Vec3 position, double time);

private:
    Vec3 lastPosition_;
    double lastTime_ = -1;
};

}  // namespace rubble::viewer
