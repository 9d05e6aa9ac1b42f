// The viewer's overlay (see overlay.h).
#include "overlay.h"

#include <imgui.h>

#include <string>

namespace rubble::viewer {

void drawOverlay(const OverlayInfo& info, DebugLayers& layers) {
    ImGui::SetNextWindowPos(ImVec2(10, 10), ImGuiCond_FirstUseEver);
    ImGui::SetNextWindowBgAlpha(0.8f);
    ImGui::Begin("Rubble", nullptr, ImGuiWindowFlags_AlwaysAutoResize);
    ImGui::TextUnformatted(info.title.c_str());
    const RuntimeStats& s = info.stats;
    ImGui::Text("physics %.1f Hz of %.0f Hz%s", s.physicsHz, info.rate, info.paused ? "  (paused)" : "");
    ImGui::Text("render  %.1f fps", info.renderFps);
    ImGui::Text("slowdown %.3f (simulated / wall)%s", s.slowdown, s.behind ? "  BEHIND" : "");
    ImGui::Text("dropped %llu steps (%.2f s), last step %.2f ms", static_cast<unsigned long long>(s.droppedSteps),
                s.droppedSeconds, s.lastStepMs);
    if (const RenderFrame* f = info.frame) {
        const Profile& p = f->profile;
        ImGui::Text("step %llu, bodies %u (%u moving, %u asleep)", static_cast<unsigned long long>(f->step),
                    f->bodyCount, p.movingCount, p.sleepingBodies);
        ImGui::Text("contacts %u manifolds, %u points; %u islands", p.manifolds, p.contactPoints, p.islands);
        ImGui::Text("drawn %zu instances, %zu triangles, %zu lines in %d draws", info.instances, info.triangles,
                    info.lines, info.drawCalls);
        if (ImGui::CollapsingHeader("Profile (last step)", ImGuiTreeNodeFlags_DefaultOpen) &&
            ImGui::BeginTable("stages", 2, ImGuiTableFlags_SizingFixedFit)) {
            for (int k = 0; k < kStageCount; ++k) {
                const StageTiming& t = p.stages[k];
                ImGui::TableNextRow();
                ImGui::TableNextColumn();
                ImGui::TextUnformatted(std::string(stageName(static_cast<Stage>(k))).c_str());
                ImGui::TableNextColumn();
                if (t.ran)
                    ImGui::Text("%8.3f ms", t.ms);
                else
                    ImGui::TextUnformatted("       -");
            }
            ImGui::TableNextRow();
            ImGui::TableNextColumn();
            ImGui::TextUnformatted("step");
            ImGui::TableNextColumn();
            ImGui::Text("%8.3f ms", p.stepMs);
            ImGui::EndTable();
        }
    }
    if (ImGui::CollapsingHeader("Debug draw", ImGuiTreeNodeFlags_DefaultOpen)) {
        ImGui::Checkbox("contacts", &layers.contacts);
        ImGui::SameLine();
        ImGui::Checkbox("AABBs", &layers.aabbs);
        ImGui::SameLine();
        ImGui::Checkbox("islands", &layers.islands);
        ImGui::SameLine();
        ImGui::Checkbox("sleeping", &layers.sleeping);
        ImGui::Checkbox("broad-phase cells", &layers.cells);
        if (layers.cells && info.frame != nullptr) {
            // Sweep-and-prune has no cells: say so, or the empty layer looks broken.
            ImGui::SameLine();
            const BroadPhaseKind ran = info.frame->profile.broadPhase;
            ImGui::TextUnformatted(ran == BroadPhaseKind::Grid            ? "(grid)"
                                   : ran == BroadPhaseKind::SweepAndPrune ? "(sweep-and-prune: static tree only)"
                                                                          : "(no broad phase ran)");
        }
        ImGui::Checkbox("joints", &layers.joints);
    }
    ImGui::Text("camera: %s", info.followCamera ? "follow" : "orbit");
    if (info.marble)
        ImGui::Text("marble: autopilot %s%s", info.autopilot ? "on" : "off", info.atGoal ? "  -- GOAL reached!" : "");
    if (info.character)
        ImGui::Text("character: autopilot %s, %d coins%s", info.autopilot ? "on" : "off", info.coins,
                    info.atEnd ? "  -- END reached!" : "");
    if (info.selected) {
        const SelectedBody& b = *info.selected;
        ImGui::Separator();
        ImGui::Text("selected body %u (generation %u): %s %s", b.id.index, b.id.generation, b.type.c_str(),
                    b.shape.c_str());
        ImGui::Text("position (%.2f, %.2f, %.2f)", b.position.x, b.position.y, b.position.z);
        ImGui::Text("velocity (%.2f, %.2f, %.2f) m/s%s", b.velocity.x, b.velocity.y, b.velocity.z,
                    b.velocityExact ? "" : " (from snapshots)");
    }
    if (ImGui::CollapsingHeader("Keys")) {
        ImGui::TextUnformatted(
            "left drag: orbit   right/middle drag: pan   wheel: zoom\n"
            "click: select body   shift+drag: pull selected body\n"
            "space: pause   N: single step   F: shoot ball   B: spawn boxes\n"
            "C: orbit / follow camera   H: hide overlay   Esc: quit\n"
            "marble: arrows steer   P: autopilot   R: restart ball\n"
            "character: arrows/WASD walk   space: jump   tab: pause   P: autopilot");
    }
    ImGui::End();
}

}  // namespace rubble::viewer
