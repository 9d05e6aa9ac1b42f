// The viewer application (see viewer_app.h): window and context, the Runtime, input, cameras, picking, the demos'
// steering, and the frame loop, interactive or headless.
#include "viewer_app.h"

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <epoxy/gl.h>
#include <imgui.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <memory>
#include <optional>
#include <stdexcept>
#include <unordered_set>

#include "camera.h"
#include "character_demo.h"
#include "gl_util.h"
#include "marble_demo.h"
#include "overlay.h"
#include "renderer.h"
#include "rubble/debug_draw.h"
#include "rubble/runtime.h"
#include "rubble/scene.h"
#include "rubble/shape_geometry.h"
#include "rubble/world.h"
#include "shape_meshes.h"

namespace rubble::viewer {

namespace {

constexpr double kHeadlessFrameSeconds = 1.0 / 60.0;

const char* shapeTypeName(ShapeType t) {
    switch (t) {
        case ShapeType::Sphere:
            return "sphere";
        case ShapeType::Box:
            return "box";
        case ShapeType::Capsule:
            return "capsule";
        case ShapeType::ConvexHull:
            return "convex hull";
        case ShapeType::Compound:
            return "compound";
        case ShapeType::TriangleMesh:
            return "triangle mesh";
        case ShapeType::Heightfield:
            return "heightfield";
    }
    return "?";
}

Rgba dynamicColor(ShapeType t) {
    switch (t) {
        case ShapeType::Box:
            return {0.93f, 0.58f, 0.20f, 1};
        case ShapeType::Sphere:
            return {0.25f, 0.55f, 0.92f, 1};
        case ShapeType::Capsule:
            return {0.35f, 0.75f, 0.38f, 1};
        case ShapeType::ConvexHull:
            return {0.70f, 0.42f, 0.85f, 1};
        case ShapeType::Compound:
            return {0.88f, 0.32f, 0.32f, 1};
        default:
            return {0.7f, 0.7f, 0.7f, 1};
    }
}

struct GlfwSession {
    GlfwSession() {
        glfwSetErrorCallback(
            [](int code, const char* text) { std::fprintf(stderr, "GLFW error %d: %s\n", code, text); });
        if (!glfwInit())
            throw std::runtime_error("cannot initialise GLFW (no display? for headless runs use xvfb-run)");
    }
    ~GlfwSession() { glfwTerminate(); }
};

class Viewer {
public:
    explicit Viewer(const ViewerOptions& options) : options_(options) {}
    ~Viewer();
    int run();

private:
    void createWindow();
    void loadWorld();
    void frameCamera(World& world);
    void registerShapes(World& world);
    void handleInput(float dt);
    void pressed(int key);
    void updateCamera(const RenderFrame& frame, float dt);
    void steerMarble(const RenderFrame& frame, float dt);
    void steerCharacter(float dt);
    void finishPick(const RenderFrame& frame);
    void updateSelection(const RenderFrame& frame);
    void applyDebugLayers();
    void renderFrame(const RenderFrame& frame, int width, int height);
    std::optional<Vec3> bodyPosition(const RenderFrame& frame, BodyId id) const;
    bool worldAvailable() const { return !runtime_->running() || runtime_->paused(); }

    GlfwSession glfw_;  // first member: terminated after everything that uses the window or its context
    ViewerOptions options_;
    std::string title_;
    GLFWwindow* window_ = nullptr;
    bool imguiReady_ = false;
    std::unique_ptr<Runtime> runtime_;
    std::unique_ptr<Renderer> renderer_;
    ShapeLibrary library_;
    InstanceLists instances_;
    std::vector<unsigned char> asleep_;

    OrbitCamera camera_;
    FollowTarget follow_;
    bool followMode_ = false;

    DebugLayers layers_;
    DebugLayers appliedLayers_;
    bool layersApplied_ = false;
    DebugLines debugLines_;
    DebugLineBatch viewerLines_;
    bool showOverlay_ = true;

    ShapeId ballShape_, boxShape_;
    std::optional<CharacterDemo> characterDemo_;
    CharacterId hero_;
    BodyId heroBody_;
    bool jumpRequested_ = false;
    bool heroAtEnd_ = false;
    std::optional<MarbleDemo> marble_;
    VelocityEstimate marbleVelocity_;
    bool marbleAtGoal_ = false;

    BodyId selected_;
    VelocityEstimate selectedVelocity_;
    std::optional<SelectedBody> selectedInfo_;
    std::optional<std::future<std::optional<RayHit>>> pendingPick_;

    // Mouse.
    double lastX_ = 0, lastY_ = 0, pressX_ = 0, pressY_ = 0;
    bool leftDown_ = false, dragged_ = false;
    float wheel_ = 0;
    std::unordered_set<int> keysDown_;
    double frameSeconds_ = 0;
};

Viewer::~Viewer() {
    runtime_.reset();  // joins the physics thread before the window goes
    renderer_.reset();
    if (imguiReady_) {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    if (window_) glfwDestroyWindow(window_);
}

void Viewer::createWindow() {
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, 4);
    const bool headless = options_.frames > 0;
    glfwWindowHint(GLFW_VISIBLE, headless ? GLFW_FALSE : GLFW_TRUE);
    window_ = glfwCreateWindow(options_.width, options_.height, title_.c_str(), nullptr, nullptr);
    if (!window_) throw std::runtime_error("cannot open a window with an OpenGL 3.3 core context");
    glfwMakeContextCurrent(window_);
    glfwSwapInterval(headless ? 0 : 1);
    if (epoxy_gl_version() < 33)
        throw std::runtime_error("OpenGL 3.3 is needed, the context has " + std::to_string(epoxy_gl_version() / 10) +
                                 "." + std::to_string(epoxy_gl_version() % 10));
    glfwSetWindowUserPointer(window_, this);
    // Installed before ImGui's, which calls it after its own.
    glfwSetScrollCallback(window_, [](GLFWwindow* w, double, double dy) {
        auto* self = static_cast<Viewer*>(glfwGetWindowUserPointer(w));
        if (!ImGui::GetIO().WantCaptureMouse) self->wheel_ += static_cast<float>(dy);
    });
    glfwSetKeyCallback(window_, [](GLFWwindow* w, int key, int, int action, int) {
        auto* self = static_cast<Viewer*>(glfwGetWindowUserPointer(w));
        if (action == GLFW_PRESS && !ImGui::GetIO().WantCaptureKeyboard) self->pressed(key);
    });
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 330 core");
    imguiReady_ = true;
    renderer_ = std::make_unique<Renderer>();
    std::printf("OpenGL %s, %s\n", reinterpret_cast<const char*>(glGetString(GL_VERSION)),
                reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
}

void Viewer::registerShapes(World& world) {
    for (BodyId id : world.bodies()) {
        const ShapeId shape = world.bodyShape(id);
        if (!library_.has(shape.index)) library_.add(shape.index, world.shapeGeometry(shape));
    }
    for (ShapeId shape : {ballShape_, boxShape_}) library_.add(shape.index, world.shapeGeometry(shape));
}

void Viewer::frameCamera(World& world) {
    // Frame what moves: the bounding sphere of the dynamic bodies' positions (or of everything when none moves).
    Vec3 lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
    for (int pass = 0; pass < 2 && lo.x > hi.x; ++pass)
        for (BodyId id : world.bodies()) {
            if (pass == 0 && world.bodyType(id) != BodyType::Dynamic) continue;
            const Vec3 p = world.position(id);
            lo = {std::min(lo.x, p.x), std::min(lo.y, p.y), std::min(lo.z, p.z)};
            hi = {std::max(hi.x, p.x), std::max(hi.y, p.y), std::max(hi.z, p.z)};
        }
    if (lo.x > hi.x) return;
    const Vec3 centre = (lo + hi) * 0.5f;
    const float radius = std::max(2.0f, 0.5f * length(hi - lo));
    camera_.target = centre;
    camera_.distance = std::min(radius / std::sin(0.5f * camera_.verticalFov) * 1.25f, 400.0f);
}

void Viewer::loadWorld() {
    std::optional<World> world;
    if (options_.marble) {
        world.emplace(MarbleDemo::makeWorld());
        marble_.emplace();
        marble_->build(*world);
        title_ = "Rubble viewer - marble demo";
    } else if (options_.character) {
        world.emplace(CharacterDemo::makeWorld());
        characterDemo_.emplace();
        characterDemo_->build(*world);
        title_ = "Rubble viewer - character demo";
    } else {
        Scene scene = loadScene(options_.scene);
        if (options_.threads >= 0) scene.settings.threads = options_.threads;
        world.emplace(scene.settings);
        instantiate(scene, *world);
        title_ = "Rubble viewer - " + scene.name + " (" + options_.scene + ")";
    }
    ballShape_ = world->createShape(SphereDef{0.3f});
    boxShape_ = world->createShape(BoxDef{{0.5f, 0.5f, 0.5f}});
    registerShapes(*world);
    if (marble_) {
        followMode_ = true;
        selected_ = marble_->ball;
        camera_.pitch = 0.7f;
        camera_.yaw = 0.0f;  // looking towards -z, up the maze's first rows
        camera_.distance = 16.0f;
        follow_.deadZone = 1.2f;
        follow_.reset(world->position(marble_->ball));
        camera_.target = follow_.lookAt;
    } else {
        frameCamera(*world);
    }
    RuntimeSettings settings;
    settings.rate = options_.rate;
    runtime_ = std::make_unique<Runtime>(std::move(*world), settings);
    if (characterDemo_) {
        hero_ = runtime_->addCharacter(characterDemo_->start);
        heroBody_ = runtime_->character(hero_)->body;
        World& w = runtime_->world();
        const ShapeId capsule = w.bodyShape(heroBody_);
        library_.add(capsule.index, w.shapeGeometry(capsule));
        followMode_ = true;
        selected_ = heroBody_;
        // From above and behind, so that the corridor's walls do not hide the character.
        camera_.pitch = 1.0f;
        camera_.yaw = 1.2f;
        camera_.distance = 12.0f;
        follow_.deadZone = 0.8f;
        follow_.reset(w.position(heroBody_));
        camera_.target = follow_.lookAt;
    }
}

void Viewer::applyDebugLayers() {
    if (layersApplied_ && layers_ == appliedLayers_) return;
    appliedLayers_ = layers_;
    layersApplied_ = true;
    DebugDrawOptions o;
    o.flags = 0;
    if (layers_.contacts) o.flags |= kDrawContacts;
    if (layers_.aabbs) o.flags |= kDrawAabbs;
    if (layers_.cells) o.flags |= kDrawBroadphaseCells;
    if (layers_.joints) o.flags |= kDrawJoints;
    if (layers_.islands) o.flags |= kDrawShapes | kDrawIslands | (layers_.sleeping ? kDrawSleeping : 0u);
    debugLines_.clear();
    if (o.flags == 0) {
        runtime_->setDebugDraw(std::nullopt);
        return;
    }
    runtime_->setDebugDraw(o);
    // While nothing steps, the stepping side draws nothing new: draw the world as it stands here.
    if (worldAvailable()) {
        DebugLineBatch batch;
        runtime_->world().debugDraw(batch, o);
        debugLines_ = std::move(batch.lines);
    }
}

std::optional<Vec3> Viewer::bodyPosition(const RenderFrame& frame, BodyId id) const {
    if (id.isNull() || id.index >= frame.slotCount() || frame.generation[id.index] != id.generation)
        return std::nullopt;
    return Vec3{frame.px[id.index], frame.py[id.index], frame.pz[id.index]};
}

void Viewer::pressed(int key) {
    switch (key) {
        case GLFW_KEY_ESCAPE:
            glfwSetWindowShouldClose(window_, GLFW_TRUE);
            break;
        case GLFW_KEY_SPACE:
            if (characterDemo_) {  // the character jumps; Tab pauses
                jumpRequested_ = true;
                break;
            }
            [[fallthrough]];
        case GLFW_KEY_TAB:
            if (runtime_->paused())
                runtime_->resume();
            else
                runtime_->pause();
            layersApplied_ = false;  // redraw debug layers from the world while paused
            break;
        case GLFW_KEY_N:
            if (!runtime_->paused()) runtime_->pause();
            runtime_->singleStep();
            layersApplied_ = false;
            break;
        case GLFW_KEY_F: {
            BodyDef def;
            def.shape = ballShape_;
            def.position = camera_.eye() + camera_.forward() * 1.0f;
            def.linearVelocity = camera_.forward() * 30.0f;
            def.material = {.friction = 0.6f, .restitution = 0.2f, .density = 3000};
            runtime_->submit(SpawnBodyCommand{def});
            break;
        }
        case GLFW_KEY_B:
            for (int i = 0; i < 4; ++i) {
                BodyDef def;
                def.shape = boxShape_;
                def.position = camera_.target + Vec3{(i % 2) * 1.2f - 0.6f, 8.0f + 1.2f * i, (i / 2) * 1.2f - 0.6f};
                def.material = {.friction = 0.6f, .restitution = 0, .density = 500};
                runtime_->submit(SpawnBodyCommand{def});
            }
            break;
        case GLFW_KEY_C:
            followMode_ = !followMode_;
            if (followMode_) follow_.reset(camera_.target);
            break;
        case GLFW_KEY_H:
            showOverlay_ = !showOverlay_;
            break;
        case GLFW_KEY_P:
            if (marble_ || characterDemo_) options_.autopilot = !options_.autopilot;
            break;
        case GLFW_KEY_R:
            if (marble_) {
                int r = 0, c = 0;
                marble_->maze.find('S', r, c);
                const Vec3 start = marble_->maze.cellCenter(r, c) + Vec3{0, MarbleDemo::kBallRadius + 0.05f, 0};
                runtime_->submit(SetTransformCommand{marble_->ball, start, Quat{}});
                runtime_->submit(SetVelocityCommand{marble_->ball, {}, {}});
                marble_->nextWaypoint = 1;
                marbleAtGoal_ = false;
            }
            break;
        default:
            break;
    }
}

void Viewer::handleInput(float /*dt*/) {
    double x = 0, y = 0;
    glfwGetCursorPos(window_, &x, &y);
    const double dx = x - lastX_, dy = y - lastY_;
    lastX_ = x;
    lastY_ = y;
    const ImGuiIO& io = ImGui::GetIO();
    int width = 1, height = 1;
    glfwGetWindowSize(window_, &width, &height);
    const bool left = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
    const bool right = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS ||
                       glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_MIDDLE) == GLFW_PRESS;
    const bool shift = glfwGetKey(window_, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS ||
                       glfwGetKey(window_, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS;
    if (left && !leftDown_ && !io.WantCaptureMouse) {
        leftDown_ = true;
        dragged_ = false;
        pressX_ = x;
        pressY_ = y;
    }
    if (leftDown_ && left) {
        if (std::hypot(x - pressX_, y - pressY_) > 4) dragged_ = true;
        if (dragged_ && !shift) camera_.orbit(static_cast<float>(-dx * 0.008), static_cast<float>(dy * 0.008));
    }
    if (leftDown_ && !left) {
        leftDown_ = false;
        if (!dragged_) {
            Vec3 origin, direction;
            camera_.rayThroughPixel(static_cast<float>(x), static_cast<float>(y), static_cast<float>(width),
                                    static_cast<float>(height), origin, direction);
            if (worldAvailable()) {
                std::promise<std::optional<RayHit>> answer;
                answer.set_value(runtime_->world().castRay(origin, direction, 1e4f));
                pendingPick_ = answer.get_future();
            } else {
                pendingPick_ = runtime_->castRay(CastRayCommand{origin, direction, 1e4f, {}});
            }
        }
    }
    if (right && !io.WantCaptureMouse) camera_.pan(static_cast<float>(dx / height), static_cast<float>(dy / height));
    if (wheel_ != 0) {
        camera_.zoom(wheel_);
        wheel_ = 0;
    }
    // Shift + drag pulls the selected body towards the cursor, on the plane through it facing the camera; the pull
    // is a velocity command, as a mouse joint would give.
    if (leftDown_ && shift && dragged_ && selectedInfo_ && !selected_.isNull() && !runtime_->paused()) {
        Vec3 origin, direction;
        camera_.rayThroughPixel(static_cast<float>(x), static_cast<float>(y), static_cast<float>(width),
                                static_cast<float>(height), origin, direction);
        const Vec3 n = camera_.forward();
        const float denom = dot(direction, n);
        if (std::fabs(denom) > 1e-4f) {
            const Vec3 target = origin + direction * (dot(selectedInfo_->position - origin, n) / denom);
            Vec3 pull = (target - selectedInfo_->position) * 8.0f;
            const float speed = length(pull);
            if (speed > 25.0f) pull = pull * (25.0f / speed);
            runtime_->submit(SetVelocityCommand{selected_, pull, {}});
        }
    }
}

void Viewer::finishPick(const RenderFrame& frame) {
    if (!pendingPick_ || pendingPick_->wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    const std::optional<RayHit> hit = pendingPick_->get();
    pendingPick_.reset();
    selected_ = hit ? hit->body : BodyId{};
    selectedVelocity_ = {};
    if (hit && followMode_) follow_.reset(camera_.target);
    if (marble_ && selected_.isNull()) selected_ = marble_->ball;
    (void)frame;
}

void Viewer::updateSelection(const RenderFrame& frame) {
    selectedInfo_.reset();
    const std::optional<Vec3> p = bodyPosition(frame, selected_);
    if (!p) return;
    SelectedBody b;
    b.id = selected_;
    const std::uint8_t flags = frame.flags[selected_.index];
    b.type = (flags & kSnapshotStatic) ? "static" : (flags & kSnapshotKinematic) ? "kinematic" : "dynamic";
    const std::uint32_t shape = frame.shape[selected_.index];
    b.shape = library_.has(shape) ? shapeTypeName(library_.type(shape)) : "?";
    b.position = *p;
    selectedVelocity_.update(*p, frame.time);
    b.velocity = selectedVelocity_.velocity;
    if (worldAvailable() && runtime_->world().isValid(selected_)) {
        b.velocity = runtime_->world().linearVelocity(selected_);
        b.velocityExact = true;
    }
    selectedInfo_ = b;
    // Its bounding box, so the selection shows in the picture too.
    viewerLines_.box(frame.transform(selected_.index),
                     library_.has(shape) ? (library_.boundsMax(shape) - library_.boundsMin(shape)) * 0.5f : Vec3{},
                     DebugColor{255, 255, 255, 255});
}

void Viewer::steerMarble(const RenderFrame& frame, float dt) {
    const std::optional<Vec3> p = bodyPosition(frame, marble_->ball);
    if (!p) return;
    marbleVelocity_.update(*p, frame.time);
    if (marble_->atGoal(*p)) marbleAtGoal_ = true;
    Vec3 force;
    if (options_.autopilot) {
        force = marble_->autopilotForce(*p, marbleVelocity_.velocity);
    } else if (window_ && options_.frames == 0) {
        auto down = [&](int key) { return glfwGetKey(window_, key) == GLFW_PRESS ? 1.0f : 0.0f; };
        force = marble_->steeringForce(down(GLFW_KEY_RIGHT) - down(GLFW_KEY_LEFT),
                                       down(GLFW_KEY_UP) - down(GLFW_KEY_DOWN), camera_.forward());
    }
    // The force acts over the frame: its impulse goes in once, whatever number of physics steps the frame spans.
    if (length(force) > 0 && !runtime_->paused()) runtime_->submit(ApplyImpulseCommand{marble_->ball, force * dt});
}

void Viewer::steerCharacter(float dt) {
    const std::optional<CharacterState> hero = runtime_->character(hero_);
    if (!hero || runtime_->paused()) return;
    CharacterDemo& demo = *characterDemo_;
    for (const BodyId coin : demo.collect(runtime_->takeEvents(), heroBody_)) runtime_->submit(RemoveBodyCommand{coin});
    if (demo.atEnd(hero->feet)) heroAtEnd_ = true;
    Vec3 walk;
    if (options_.autopilot) {
        walk = demo.autopilotWalk(*hero);
    } else if (window_ && options_.frames == 0) {
        auto down = [&](int a, int b) {
            return glfwGetKey(window_, a) == GLFW_PRESS || glfwGetKey(window_, b) == GLFW_PRESS ? 1.0f : 0.0f;
        };
        walk = demo.walkVelocity(down(GLFW_KEY_RIGHT, GLFW_KEY_D) - down(GLFW_KEY_LEFT, GLFW_KEY_A),
                                 down(GLFW_KEY_UP, GLFW_KEY_W) - down(GLFW_KEY_DOWN, GLFW_KEY_S), camera_.forward());
    }
    runtime_->submit(WalkCharacterCommand{hero_, walk, jumpRequested_ ? CharacterDemo::kJumpSpeed : 0.0f});
    jumpRequested_ = false;
    runtime_->submit(demo.moveLift(*hero, dt));
}

void Viewer::updateCamera(const RenderFrame& frame, float dt) {
    if (!followMode_) return;
    const std::optional<Vec3> p = bodyPosition(frame, selected_);
    if (!p) return;
    follow_.update(*p, dt);
    camera_.target = follow_.lookAt;
}

void Viewer::renderFrame(const RenderFrame& frame, int width, int height) {
    if (frame.slotCount() > asleep_.size()) asleep_.resize(frame.slotCount());
    const bool tintSleeping = layers_.sleeping;
    const std::uint32_t highlight = selected_.isNull() ? ~0u : selected_.index;
    const std::uint32_t ball = marble_ ? marble_->ball.index : ~0u;
    const std::uint32_t beacon = marble_ ? marble_->beacon.index : ~0u;
    const std::uint32_t floor = marble_ ? marble_->floorBody.index : ~0u;
    const std::uint32_t walls = marble_ ? marble_->wallBody.index : ~0u;
    const std::uint32_t hero = characterDemo_ ? heroBody_.index : ~0u;
    const auto isCoin = [&](std::uint32_t slot) {
        if (!characterDemo_) return false;
        for (const BodyId coin : characterDemo_->coins)
            if (coin.index == slot) return true;
        return false;
    };
    collectInstances(
        frame, library_,
        [&](std::uint32_t slot, ShapeType type) -> Rgba {
            const std::uint8_t flags = frame.flags[slot];
            if (slot == beacon) return {0.2f, 0.95f, 0.3f, 1};
            if (slot == hero) return {0.98f, 0.82f, 0.12f, 1};
            if (isCoin(slot)) return {1.0f, 0.62f, 0.05f, 1};
            if (slot == floor) return {0.45f, 0.62f, 0.85f, 0.85f};
            if (slot == walls) return {0.22f, 0.27f, 0.45f, 1};
            if (flags & kSnapshotStatic) return {0.56f, 0.57f, 0.58f, 0.88f};  // checkered ground
            Rgba c = (flags & kSnapshotKinematic) ? Rgba{0.35f, 0.55f, 1.0f, 1} : dynamicColor(type);
            // A little brightness per body, fixed by its slot, so neighbours of one colour part.
            const float shade = 0.9f + 0.2f * static_cast<float>((slot * 2654435761u) >> 24) / 255.0f;
            c = {std::min(1.0f, c.r * shade), std::min(1.0f, c.g * shade), std::min(1.0f, c.b * shade), 1};
            if (slot == ball) c = {0.85f, 0.12f, 0.15f, 1};
            if (flags & kSnapshotFrozen) c = {1, 0, 0, 1};
            if (tintSleeping && (flags & kSnapshotAsleep)) c = {0.5f, 0.36f, 0.78f, 1};
            if (slot == highlight && slot != ball)
                c = {std::min(1.0f, c.r + 0.3f), std::min(1.0f, c.g + 0.3f), std::min(1.0f, c.b + 0.3f), 1};
            return c;
        },
        instances_);
    renderer_->uploadMeshes(library_);
    const float aspect = static_cast<float>(width) / static_cast<float>(std::max(1, height));
    const Mat4 viewProjection = multiply(camera_.projection(aspect), camera_.view());
    renderer_->draw(instances_, {&debugLines_, &viewerLines_.lines}, viewProjection, camera_.eye(), width, height);
}

int Viewer::run() {
    loadWorld();
    createWindow();
    const bool headless = options_.frames > 0;
    showOverlay_ = options_.overlay;
    if (!options_.layers.empty()) {
        const std::string& l = options_.layers;
        layers_ = {.contacts = l.find("contacts") != std::string::npos,
                   .aabbs = l.find("aabbs") != std::string::npos,
                   .islands = l.find("islands") != std::string::npos,
                   .sleeping = l.find("sleeping") != std::string::npos,
                   .cells = l.find("cells") != std::string::npos,
                   .joints = l.find("joints") != std::string::npos};
    }
    std::unique_ptr<OffscreenTarget> target;
    if (headless)
        target = std::make_unique<OffscreenTarget>(options_.width, options_.height, 4);
    else
        runtime_->start();

    using Clock = std::chrono::steady_clock;
    auto last = Clock::now();
    for (int frameIndex = 0; headless ? frameIndex < options_.frames : !glfwWindowShouldClose(window_); ++frameIndex) {
        const auto now = Clock::now();
        const double wall = std::chrono::duration<double>(now - last).count();
        last = now;
        // Averaged over frame times (not rates), from the second frame on: the first has no frame before it.
        if (frameIndex == 1) frameSeconds_ = wall;
        if (frameIndex > 1) frameSeconds_ = 0.95 * frameSeconds_ + 0.05 * wall;
        const double renderFps = frameSeconds_ > 0 ? 1 / frameSeconds_ : 0;
        const float dt = headless ? static_cast<float>(kHeadlessFrameSeconds) : static_cast<float>(std::min(wall, 0.1));

        glfwPollEvents();
        if (!headless) handleInput(dt);
        applyDebugLayers();
        if (headless) runtime_->advance(kHeadlessFrameSeconds);
        runtime_->takeDebugLines(debugLines_);
        const RenderFrame& frame = headless || runtime_->paused() ? runtime_->latest(1.0f) : runtime_->interpolate();
        finishPick(frame);
        viewerLines_.lines.clear();
        updateSelection(frame);
        if (marble_) steerMarble(frame, dt);
        if (characterDemo_) steerCharacter(dt);
        updateCamera(frame, dt);
        for (const std::string& error : runtime_->takeInputErrors()) std::fprintf(stderr, "input: %s\n", error.c_str());

        int width = options_.width, height = options_.height;
        if (headless)
            target->bind();
        else
            glfwGetFramebufferSize(window_, &width, &height);
        renderFrame(frame, width, height);

        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        if (headless) ImGui::GetIO().DisplaySize = ImVec2(static_cast<float>(width), static_cast<float>(height));
        ImGui::NewFrame();
        if (showOverlay_) {
            OverlayInfo info;
            info.title = title_;
            info.renderFps = renderFps;
            info.frame = &frame;
            info.stats = runtime_->stats();
            info.rate = options_.rate;
            info.paused = runtime_->paused();
            info.followCamera = followMode_;
            info.marble = marble_.has_value();
            info.autopilot = options_.autopilot;
            info.atGoal = marbleAtGoal_;
            info.character = characterDemo_.has_value();
            info.coins = characterDemo_ ? characterDemo_->coinsCollected : 0;
            info.atEnd = heroAtEnd_;
            info.instances = renderer_->stats().instances;
            info.triangles = renderer_->stats().triangles;
            info.lines = renderer_->stats().lines;
            info.drawCalls = renderer_->stats().drawCalls;
            info.selected = selectedInfo_;
            drawOverlay(info, layers_);
        }
        ImGui::Render();
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
        if (!headless) glfwSwapBuffers(window_);
    }

    if (headless) {
        const std::vector<unsigned char> pixels = target->readPixels();
        if (!options_.screenshot.empty()) {
            writePng(options_.screenshot, options_.width, options_.height, pixels);
            std::printf("screenshot %s (%dx%d) after %d frames, physics step %llu%s\n", options_.screenshot.c_str(),
                        options_.width, options_.height, options_.frames,
                        static_cast<unsigned long long>(runtime_->stats().steps),
                        marble_          ? (marbleAtGoal_ ? ", marble at the goal" : ", marble on its way")
                        : characterDemo_ ? (heroAtEnd_ ? ", character at the end" : ", character on its way")
                                         : "");
            if (characterDemo_)
                std::printf("coins %d of %zu\n", characterDemo_->coinsCollected, characterDemo_->coins.size());
        }
    } else {
        runtime_->stop();
    }
    return 0;
}

}  // namespace

int runViewer(const ViewerOptions& options) {
    Viewer viewer(options);
    return viewer.run();
}

}  // namespace rubble::viewer
