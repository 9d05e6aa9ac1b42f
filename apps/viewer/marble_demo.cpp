// The marble demo (see marble_demo.h).
#include "marble_demo.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <stdexcept>

#include "rubble/world.h"

namespace rubble::viewer {

namespace {

/// Appends quad a b c d (a convex polygon in order) as two triangles wound so their normal points along `outward`.
void addQuad(TriangleMeshDef& mesh, Vec3 a, Vec3 b, Vec3 c, Vec3 d, Vec3 outward) {
    if (dot(cross(b - a, c - a), outward) < 0) std::swap(b, d);
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), {a, b, c, d});
    mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
}

}  // namespace

MarbleMaze MarbleMaze::standard() {
    // The first rows slope down (kRampRows), so the ball starts rolling down a ramp; the corridors were drawn by
    // hand and solve() finds the way through.
    return {{
        "###############",
        "#S#...#.......#",
        "#.#.#.#.#####.#",
        "#.#.#...#...#.#",
        "#.#.#####.#.#.#",
        "#...#.....#...#",
        "#####.#######.#",
        "#.....#.....#.#",
        "#.#####.###.#.#",
        "#.#...#...#.#.#",
        "#.#.#.###.#.#.#",
        "#...#.#...#...#",
        "###.#.#.#####.#",
        "#.....#......G#",
        "###############",
    }};
}

bool MarbleMaze::isWall(int row, int column) const {
    if (row < 0 || column < 0 || row >= rows() || column >= columns()) return true;
    return layout[row][column] == '#';
}

float MarbleMaze::cornerHeight(int row, int /*column*/) const {
    if (row >= kRampRows) return 0;
    return kRampDrop * static_cast<float>(kRampRows - row) / static_cast<float>(kRampRows);
}

Vec3 MarbleMaze::cellCenter(int row, int column) const {
    const float x = (static_cast<float>(column) + 0.5f - 0.5f * static_cast<float>(columns())) * kCellSize;
    const float z = (static_cast<float>(row) + 0.5f - 0.5f * static_cast<float>(rows())) * kCellSize;
    const float y = 0.25f * (cornerHeight(row, column) + cornerHeight(row + 1, column) + cornerHeight(row, column + 1) +
                             cornerHeight(row + 1, column + 1));
    return {x, y, z};
}

void MarbleMaze::find(char what, int& row, int& column) const {
    for (row = 0; row < rows(); ++row)
        for (column = 0; column < columns(); ++column)
            if (layout[row][column] == what) return;
    throw std::logic_error(std::string("marble maze has no '") + what + "' cell");
}

namespace {

/// Builds the floor (walls = false) or the walls of `maze`.
TriangleMeshDef buildMazeMesh(const MarbleMaze& maze, bool walls) {
    using M = MarbleMaze;
    TriangleMeshDef mesh;
    const float x0 = -0.5f * static_cast<float>(maze.columns()) * M::kCellSize;
    const float z0 = -0.5f * static_cast<float>(maze.rows()) * M::kCellSize;
    auto corner = [&](int r, int c, float lift) {
        return Vec3{x0 + static_cast<float>(c) * M::kCellSize, maze.cornerHeight(r, c) + lift,
                    z0 + static_cast<float>(r) * M::kCellSize};
    };
    const Vec3 up{0, 1, 0};
    for (int r = 0; r < maze.rows(); ++r)
        for (int c = 0; c < maze.columns(); ++c) {
            if (!maze.isWall(r, c)) {
                if (!walls)
                    addQuad(mesh, corner(r, c, 0), corner(r + 1, c, 0), corner(r + 1, c + 1, 0), corner(r, c + 1, 0),
                            up);
                continue;
            }
            if (!walls) continue;
            const float h = M::kWallHeight;
            addQuad(mesh, corner(r, c, h), corner(r + 1, c, h), corner(r + 1, c + 1, h), corner(r, c + 1, h), up);
            // Sides between two walls are inside the wall: only those facing a floor cell or the outside are built.
            struct Side {
                int dr, dc;
                int r0, c0, r1, c1;  // the side's two corners, relative to the cell
            };
            const Side sides[] = {{-1, 0, 0, 0, 0, 1}, {1, 0, 1, 0, 1, 1}, {0, -1, 0, 0, 1, 0}, {0, 1, 0, 1, 1, 1}};
            for (const Side& s : sides) {
                const int nr = r + s.dr, nc = c + s.dc;
                const bool outside = nr < 0 || nc < 0 || nr >= maze.rows() || nc >= maze.columns();
                if (!outside && maze.isWall(nr, nc)) continue;
                addQuad(mesh, corner(r + s.r0, c + s.c0, 0), corner(r + s.r1, c + s.c1, 0),
                        corner(r + s.r1, c + s.c1, h), corner(r + s.r0, c + s.c0, h),
                        Vec3{static_cast<float>(s.dc), 0, static_cast<float>(s.dr)});
            }
        }
    return mesh;
}

}  // namespace

TriangleMeshDef MarbleMaze::buildFloor() const { return buildMazeMesh(*this, false); }
TriangleMeshDef MarbleMaze::buildWalls() const { return buildMazeMesh(*this, true); }

std::vector<Vec3> MarbleMaze::solve() const {
    int sr = 0, sc = 0, gr = 0, gc = 0;
    find('S', sr, sc);
    find('G', gr, gc);
    std::vector<int> from(static_cast<std::size_t>(rows() * columns()), -1);
    std::deque<int> queue{sr * columns() + sc};
    from[queue.front()] = queue.front();
    while (!queue.empty()) {
        const int cell = queue.front();
        queue.pop_front();
        const int r = cell / columns(), c = cell % columns();
        if (r == gr && c == gc) break;
        const int steps[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
        for (const auto& d : steps) {
            const int nr = r + d[0], nc = c + d[1];
            if (isWall(nr, nc) || from[nr * columns() + nc] >= 0) continue;
            from[nr * columns() + nc] = cell;
            queue.push_back(nr * columns() + nc);
        }
    }
    std::vector<Vec3> path;
    if (from[gr * columns() + gc] < 0) return path;
    for (int cell = gr * columns() + gc;; cell = from[cell]) {
        path.push_back(cellCenter(cell / columns(), cell % columns()));
        if (cell == sr * columns() + sc) break;
    }
    std::reverse(path.begin(), path.end());
    return path;
}

World MarbleDemo::makeWorld() {
    WorldSettings settings;
    settings.threads = 1;
    settings.effects = EffectSet{}.with(Effect::Gravity).with(Effect::Rotation).with(Effect::Friction);
    return World(settings);
}

void MarbleDemo::build(World& world) {
    BodyDef mazeDef;
    mazeDef.type = BodyType::Static;
    mazeDef.material = {.friction = 0.9f, .restitution = 0, .density = 1000};
    mazeDef.shape = world.createShape(maze.buildFloor());
    floorBody = world.createBody(mazeDef);
    mazeDef.shape = world.createShape(maze.buildWalls());
    mazeDef.material.friction = 0.3f;  // walls guide the ball rather than grab it
    wallBody = world.createBody(mazeDef);

    int r = 0, c = 0;
    maze.find('S', r, c);
    BodyDef ballDef;
    ballDef.shape = world.createShape(SphereDef{kBallRadius});
    ballDef.position = maze.cellCenter(r, c) + Vec3{0, kBallRadius + 0.05f, 0};
    ballDef.material = {.friction = 0.9f, .restitution = 0.1f, .density = 1000};
    // Rolling resistance stands in as damping, so a ball left alone comes to rest on the flat.
    ballDef.linearDamping = 0.3f;
    ballDef.angularDamping = 0.3f;
    ballDef.allowSleep = false;
    ball = world.createBody(ballDef);
    ballMass = world.massProperties(ball).mass;

    maze.find('G', r, c);
    BodyDef beaconDef;
    beaconDef.type = BodyType::Static;
    beaconDef.shape = world.createShape(SphereDef{0.35f});
    beaconDef.position = maze.cellCenter(r, c) + Vec3{0, 2.0f, 0};
    beaconDef.filter = {.category = 0, .mask = 0};  // a marker: nothing collides with it, queries skip it
    beacon = world.createBody(beaconDef);

    path = maze.solve();
    nextWaypoint = 1;
}

Vec3 MarbleDemo::steeringForce(float right, float forward, Vec3 cameraForward) const {
    Vec3 ahead{cameraForward.x, 0, cameraForward.z};
    const float len = length(ahead);
    ahead = len > 1e-6f ? ahead / len : Vec3{0, 0, -1};
    const Vec3 side{-ahead.z, 0, ahead.x};  // ahead x up: to the camera's right
    Vec3 push = side * right + ahead * forward;
    const float amount = length(push);
    if (amount > 1) push = push / amount;
    return push * (kSteerAcceleration * ballMass);
}

Vec3 MarbleDemo::autopilotForce(Vec3 position, Vec3 velocity) {
    if (path.empty()) return {};
    auto flatDistance = [](Vec3 a, Vec3 b) { return std::hypot(a.x - b.x, a.z - b.z); };
    // Passing a waypoint (or being nearer a later one, after a bounce) moves the aim on.
    for (std::size_t k = nextWaypoint; k < path.size() && k < nextWaypoint + 3; ++k)
        if (flatDistance(position, path[k]) < 0.35f * MarbleMaze::kCellSize) nextWaypoint = k + 1;
    const Vec3 aim = path[std::min(nextWaypoint, path.size() - 1)];
    Vec3 toward{aim.x - position.x, 0, aim.z - position.z};
    const float distance = length(toward);
    const float cruise = 2.5f;  // m/s: slow enough to take the corners without hitting the walls hard
    const Vec3 desired = distance > 1e-4f ? toward * (std::min(cruise, 2.0f * distance) / distance) : Vec3{};
    Vec3 accel = (desired - Vec3{velocity.x, 0, velocity.z}) * 4.0f;
    const float magnitude = length(accel);
    if (magnitude > kSteerAcceleration) accel = accel * (kSteerAcceleration / magnitude);
    return accel * ballMass;
}

bool MarbleDemo::atGoal(Vec3 position) const {
    int r = 0, c = 0;
    maze.find('G', r, c);
    const Vec3 centre = maze.cellCenter(r, c);
    const float half = 0.5f * MarbleMaze::kCellSize;
    return std::fabs(position.x - centre.x) < half && std::fabs(position.z - centre.z) < half &&
           std::fabs(position.y - centre.y) < 2.0f;
}

void VelocityEstimate::update(Vec3 position, double time) {
    if (lastTime_ >= 0 && time > lastTime_) {
        velocity = (position - lastPosition_) / static_cast<float>(time - lastTime_);
        valid = true;
    }
    if (time != lastTime_) {
        lastPosition_ = position;
        lastTime_ = time;
    }
}

}  // namespace rubble::viewer
