#pragma once
// The viewer application: a window (or a hidden one for headless runs), the physics Runtime, input, cameras, the
// renderer and the overlay.
#include <string>

namespace rubble::viewer {

struct ViewerOptions {
    std::string scene;       ///< scene file; empty with `marble`
    bool marble = false;     ///< the marble demo instead of a scene
    bool character = false;  ///< the character demo instead of a scene
    /// Headless: render this many frames, stepping physics by a fixed 1/60 s per frame on this thread (so the
    /// result does not depend on the machine's speed), then write `screenshot`. 0: interactive.
    int frames = 0;
    std::string screenshot;
    int width = 1280, height = 720;
    double rate = 120;  ///< physics steps per second
    int threads = -1;   ///< worker threads (-1: the scene's setting)
    bool overlay = true;
    /// Demos: the marble follows the way through the maze, the character walks the course, by themselves.
    bool autopilot = false;
    /// Debug layers to start with: any of "contacts", "aabbs", "islands", "sleeping", "cells", "joints"
    /// (comma-separated).
    std::string layers;
};

/// Runs the viewer; returns the process exit code. Throws on errors (bad scene, no OpenGL 3.3 context).
int runViewer(const ViewerOptions& options);

}  // namespace rubble::viewer
