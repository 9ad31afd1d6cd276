// C++17: the trainer through tissue.h. The appendix is cut (a drawn path, then a blade sweep)
// and sutured, its surface read back after each change; then a probe presses it while a
// haptic thread sets the probe's pose and asks for the force at 1 kHz, the physics stepping at
// 100 Hz on another thread: the force opposes the press and moves smoothly between steps. The
// appendix's demonstration plays with its events arriving by their own kinds.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "check.hpp"
#include "tissue.h"

namespace {


struct Body {
    tissue_body* p = nullptr;
    Body() = default;
    Body(const Body&) = delete;
    Body& operator=(const Body&) = delete;
    ~Body() { tissue_body_free(p); }
};

// The surface as a host keeps it: copied only when a revision changed.
struct Surface {
    std::vector<float> xyz;
    std::vector<uint32_t> triangles;
    uint64_t positions_revision = 0, topology_revision = 0;
    int topology_copies = 0;

    void update(tissue_body* body) {
        tissue_body_info info{};
        ok(tissue_body_get_info(body, &info), "info");
        if (info.positions_revision != positions_revision) {
            xyz.resize(3 * info.nodes);
            ok(tissue_body_copy_positions(body, xyz.data(), xyz.size(), &positions_revision),
               "positions");
        }
        if (info.topology_revision != topology_revision) {
            triangles.resize(3 * info.triangles);
            ok(tissue_body_copy_triangles(body, triangles.data(), triangles.size(),
                                          &topology_revision),
               "triangles");
            ++topology_copies;
        }
    }

    // The highest node within 0.3 cm of (x, z) horizontally.
    float top(float x, float z) const {
        float y = -1e9f;
        for (size_t i = 0; i + 2 < xyz.size(); i += 3) {
            if (std::hypot(xyz[i] - x, xyz[i + 2] - z) < 0.3f) {
                y = std::max(y, xyz[i + 1]);
            }
        }
        return y;
    }
};

// Drains the body's events, counting those of `kind`.
int drain(tissue_body* body, tissue_event_kind kind) {
    int n = 0;
    tissue_event e{};
    bool has = false;
    while (tissue_body_next_event(body, &e, &has) == TISSUE_OK && has) {
        std::printf("  event at step %llu: %s\n", static_cast<unsigned long long>(e.step), e.text);
        n += e.kind == kind ? 1 : 0;
    }
    return n;
}

void surgery() {
    Body body;
    ok(tissue_body_new_shipped(TISSUE_ORGAN_APPENDIX, &body.p), "appendix");
    // Self-collision (issue 35) is on by default: it holds the wound's walls below.
    tissue_body_info first{};
    ok(tissue_body_get_info(body.p, &first), "info");
    check(first.self_collision, "self-collision is on by default");
    for (int i = 0; i < 20; ++i) {
        ok(tissue_body_step(body.p, nullptr), "step");
    }
    Surface s;
    s.update(body.p);
    const size_t triangles_before = s.triangles.size() / 3;
    const uint64_t topology_before = s.topology_revision;

    // The scalpel drawn across the top at x = 0, seen from above.
    std::vector<float> path;
    for (int i = 0; i <= 10; ++i) {
        const float z = -1.3f + 0.26f * static_cast<float>(i);
        path.insert(path.end(), {0.0f, s.top(0.0f, z), z});
    }
    const float down[3] = {0.0f, -1.0f, 0.0f};
    size_t segments = 0;
    ok(tissue_body_cut(body.p, path.data(), path.size() / 3, down, &segments), "cut");
    for (size_t i = 0; i < segments + 5; ++i) {
        ok(tissue_body_step(body.p, nullptr), "step");
    }
    const int cuts = drain(body.p, TISSUE_EVENT_CUT_ADVANCED);
    s.update(body.p);
    std::printf("drawn cut: %zu segments, %d cut events, surface %zu -> %zu triangles\n",
                segments, cuts, triangles_before, s.triangles.size() / 3);
    check(cuts > 0, "the cut advanced");
    check(s.topology_revision != topology_before && s.triangles.size() / 3 > triangles_before,
          "the surface changed and was copied again");

    // Self-collision (issue 35), on by default: the wound's two walls, their nodes duplicated in
    // place by the cut, are held apart by self-contacts; switched off, there are none; then on
    // again.
    tissue_body_info self_info{};
    ok(tissue_body_get_info(body.p, &self_info), "info");
    uint64_t crossing = 0;
    ok(tissue_body_self_intersections(body.p, &crossing), "self-intersections");
    std::printf("after the cut: self-collision %s, %llu self-contacts (%llu active), %llu "
                "self-intersections\n",
                self_info.self_collision ? "on" : "off",
                static_cast<unsigned long long>(self_info.self_contacts),
                static_cast<unsigned long long>(self_info.self_contacts_active),
                static_cast<unsigned long long>(crossing));
    check(self_info.self_collision && self_info.self_contacts > 0,
          "self-collision is on and holds the wound's walls");
    ok(tissue_body_set_self_collision(body.p, false), "self-collision off");
    ok(tissue_body_step(body.p, nullptr), "step");
    ok(tissue_body_get_info(body.p, &self_info), "info");
    check(!self_info.self_collision && self_info.self_contacts == 0,
          "switched off: no self-contacts");
    ok(tissue_body_set_self_collision(body.p, true), "self-collision on");

    // The needle across the wound, 0.3 cm either side.
    const float a[3] = {-0.3f, s.top(-0.3f, 0.0f), 0.0f};
    const float b[3] = {0.3f, s.top(0.3f, 0.0f), 0.0f};
    tissue_event sutured{};
    ok(tissue_body_suture(body.p, a, b, &sutured), "suture");
    std::printf("suture: %s\n", sutured.text);
    check(sutured.kind == TISSUE_EVENT_SUTURE_PLACED, "the suture was placed");
    drain(body.p, TISSUE_EVENT_SUTURE_PLACED);
    // The same stitch again is refused, naming why.
    check(tissue_body_suture(body.p, a, b, nullptr) == TISSUE_INVALID_ARGUMENT &&
              last_error().find("already there") != std::string::npos,
          "a second suture at the same place is refused");
    // A path of a million points is refused before it is read (the NULL path is never touched).
    check(tissue_body_cut(body.p, nullptr, 1000000, down, nullptr) == TISSUE_INVALID_ARGUMENT &&
              last_error().find("at most 10000") != std::string::npos,
          "a path of a million points is refused before it is read");

    // A blade sweep across the organ at x = 2: the blade's plane x = 0 in its frame, its edge
    // 1 cm under the pose's origin.
    const float y = s.top(2.0f, 0.0f);
    const tissue_pose from{{0, 0, 0, 1}, {2.0f, y, -1.5f}};
    const tissue_pose to{{0, 0, 0, 1}, {2.0f, y, 1.5f}};
    const uint64_t topology = s.topology_revision;
    ok(tissue_body_cut_sweep(body.p, &from, &to), "blade sweep");
    const int swept = drain(body.p, TISSUE_EVENT_CUT_ADVANCED);
    for (int i = 0; i < 10; ++i) {
        ok(tissue_body_step(body.p, nullptr), "step");
    }
    s.update(body.p);
    std::printf("blade sweep: %d cut events; %d topology copies in all\n", swept,
                s.topology_copies);
    check(swept > 0 && s.topology_revision != topology, "the sweep cut");
    tissue_body_info info{};
    ok(tissue_body_get_info(body.p, &info), "info");
    std::printf("after surgery: %llu nodes, %llu tets, volume drift %.3f %%, step %.2f ms "
                "(median)\n",
                static_cast<unsigned long long>(info.nodes),
                static_cast<unsigned long long>(info.tets), 100.0 * info.volume_drift,
                info.step_ms_median);
    check(std::isfinite(info.volume_drift) && std::fabs(info.volume_drift) < 0.1, "volume held");

    // An unknown tool, and a pose that is no rotation, are errors with messages.
    float f[3];
    check(tissue_tool_force(body.p, 3, f, nullptr) == TISSUE_INVALID_ARGUMENT, "no tool 3");
    const tissue_pose bad{{0, 0, 0, 2}, {0, 0, 0}};
    const float tip[3] = {0, 0, 0}, end[3] = {0, 1, 0};
    check(tissue_body_add_capsule(body.p, tip, end, 0.3f, &bad, nullptr) ==
              TISSUE_INVALID_ARGUMENT,
          "bad quaternion");
    check(last_error().find("unit quaternion") != std::string::npos, last_error());
}

struct Sample {
    double t;
    float y;
    float f[3];
    uint64_t step;
};

void force_loop() {
    Body body;
    ok(tissue_body_new_shipped(TISSUE_ORGAN_APPENDIX, &body.p), "appendix");
    for (int i = 0; i < 20; ++i) {
        ok(tissue_body_step(body.p, nullptr), "settle");
    }
    // A probe: a vertical capsule of radius 0.3 cm, its tip's centre at the pose's origin.
    const float tip[3] = {0, 0, 0}, top[3] = {0, 3, 0};
    const float x = 1.5f;
    const tissue_pose start{{0, 0, 0, 1}, {x, 2.6f, 0}};
    uint32_t probe = 0;
    ok(tissue_body_add_capsule(body.p, tip, top, 0.3f, &start, &probe), "probe");

    // The probe's path: down at 1 cm/s from y = 2.6 to 1.9 (its tip 0.4 cm into the 2 cm
    // organ), held, then back up.
    auto height = [](double t) {
        if (t < 0.7) return 2.6 - t;
        if (t < 1.2) return 1.9;
        return std::min(2.6, 1.9 + (t - 1.2));
    };
    const double duration = 1.8;
    std::atomic<bool> done{false};
    std::atomic<int> steps{0};
    std::vector<Sample> samples;
    samples.reserve(4000);

    const auto t0 = std::chrono::steady_clock::now();
    auto seconds = [&] {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    };
    std::thread haptic([&] {
        auto next = std::chrono::steady_clock::now();
        while (true) {
            const double t = seconds();
            if (t >= duration) break;
            const tissue_pose pose{{0, 0, 0, 1}, {x, static_cast<float>(height(t)), 0}};
            Sample s{t, pose.translation[1], {0, 0, 0}, 0};
            if (tissue_tool_set_pose(body.p, probe, &pose) != TISSUE_OK ||
                tissue_tool_force(body.p, probe, s.f, &s.step) != TISSUE_OK) {
                std::fprintf(stderr, "haptic call failed: %s\n", last_error().c_str());
                ++failures;
                break;
            }
            samples.push_back(s);
            next += std::chrono::microseconds(1000);
            std::this_thread::sleep_until(next);
        }
        done = true;
    });
    // The physics: a step every 10 ms.
    auto next = std::chrono::steady_clock::now();
    while (!done) {
        if (tissue_body_step(body.p, nullptr) != TISSUE_OK) {
            std::fprintf(stderr, "step failed: %s\n", last_error().c_str());
            ++failures;
            break;
        }
        ++steps;
        next += std::chrono::milliseconds(10);
        std::this_thread::sleep_until(next);
    }
    haptic.join();

    // The figures.
    const double elapsed = samples.empty() ? 1.0 : samples.back().t - samples.front().t;
    const double rate = static_cast<double>(samples.size() - 1) / elapsed;
    float peak = 0.0f, max_jump = 0.0f, max_step_change = 0.0f;
    // While the probe moves: how much of the force's change arrives at step boundaries (all of
    // it if the force were held from step to step).
    double at_steps = 0.0, in_all = 0.0;
    size_t against = 0, loaded = 0, moving = 0, varied = 0;
    for (size_t i = 0; i < samples.size(); ++i) {
        const Sample& s = samples[i];
        const float m = std::sqrt(s.f[0] * s.f[0] + s.f[1] * s.f[1] + s.f[2] * s.f[2]);
        peak = std::max(peak, m);
        if (m > 0.01f) {
            ++loaded;
            against += s.f[1] > 0.0f ? 1 : 0;
        }
        if (i == 0) continue;
        const Sample& p = samples[i - 1];
        const float d = std::sqrt((s.f[0] - p.f[0]) * (s.f[0] - p.f[0]) +
                                  (s.f[1] - p.f[1]) * (s.f[1] - p.f[1]) +
                                  (s.f[2] - p.f[2]) * (s.f[2] - p.f[2]));
        max_jump = std::max(max_jump, d);
        if (s.y != p.y) {
            in_all += d;
            at_steps += s.step != p.step ? d : 0.0f;
        }
        if (s.step != p.step) {
            max_step_change = std::max(max_step_change, d);
        } else if (m > 0.01f && s.y != p.y) {
            // Between two steps, the probe moved: does the force follow it?
            ++moving;
            varied += d > 0.0f ? 1 : 0;
        }
    }
    std::printf("force loop: %zu haptic samples in %.2f s = %.0f Hz while %d steps ran (%.0f "
                "Hz); peak %.3f N; %zu/%zu loaded samples push back up; force varied in "
                "%zu/%zu samples between steps while the probe moved; largest change between "
                "consecutive samples %.4f N (%.1f %% of the peak; at a step %.4f N); %.0f %% of the "
                "change while moving came at step boundaries (100 %% if held)\n",
                samples.size(), elapsed, rate, steps.load(),
                steps.load() / std::max(elapsed, 1e-9), peak, against, loaded, varied, moving,
                max_jump, 100.0 * max_jump / std::max(peak, 1e-9f), max_step_change,
                100.0 * at_steps / std::max(in_all, 1e-12));
    check(rate > 500.0, "the haptic loop ran at " + std::to_string(rate) + " Hz");
    check(at_steps < 0.5 * in_all, "most of the change comes between steps");
    check(peak > 0.01f, "the probe felt the tissue: " + std::to_string(peak) + " N");
    check(loaded > 100 && against == loaded, "the force opposes the press");
    check(moving > 100 && varied * 10 >= moving * 9, "the force follows the probe between steps");
    check(max_jump < 0.2f * peak, "no jump: " + std::to_string(max_jump) + " N");
    // Backed off: nothing.
    float f[3];
    ok(tissue_tool_force(body.p, probe, f, nullptr), "force");
    check(std::fabs(f[1]) < 1e-3f, "free again: " + std::to_string(f[1]));
}

// The appendix's demonstration played through the C ABI: its events arrive with their own
// kinds (started, cuts, the tip off, three stitches, finished), none as TISSUE_EVENT_OTHER.
void demonstration() {
    Body body;
    ok(tissue_body_new_shipped(TISSUE_ORGAN_APPENDIX, &body.p), "appendix");
    ok(tissue_body_play(body.p), "play");
    check(tissue_body_play(body.p) == TISSUE_INVALID_ARGUMENT, "a second play is refused");
    int counts[16] = {0};
    int steps = 0;
    bool finished = false;
    while (!finished && steps < 400) {
        ok(tissue_body_step(body.p, nullptr), "step");
        ++steps;
        tissue_event e{};
        bool has = false;
        while (tissue_body_next_event(body.p, &e, &has) == TISSUE_OK && has) {
            const int k = static_cast<int>(e.kind);
            counts[k >= 0 && k < 16 ? k : 15] += 1;
            finished = finished || e.kind == TISSUE_EVENT_DEMO_FINISHED;
        }
    }
    std::printf("demonstration: %d steps; started %d, cut %d, pieces %d, sutures %d, finished "
                "%d, other %d\n",
                steps, counts[TISSUE_EVENT_DEMO_STARTED], counts[TISSUE_EVENT_CUT_ADVANCED],
                counts[TISSUE_EVENT_PIECE_DETACHED], counts[TISSUE_EVENT_SUTURE_PLACED],
                counts[TISSUE_EVENT_DEMO_FINISHED], counts[TISSUE_EVENT_OTHER]);
    check(finished && steps == 200, "the demonstration ends after its 200 steps");
    check(counts[TISSUE_EVENT_DEMO_STARTED] == 1, "one demo_started event");
    check(counts[TISSUE_EVENT_DEMO_FINISHED] == 1, "one demo_finished event");
    check(counts[TISSUE_EVENT_CUT_ADVANCED] > 0, "the demonstration's cuts arrive as cuts");
    check(counts[TISSUE_EVENT_PIECE_DETACHED] > 0, "the tip comes off");
    check(counts[TISSUE_EVENT_SUTURE_PLACED] == 3, "three stitches");
    check(counts[TISSUE_EVENT_OTHER] == 0 && counts[15] == 0, "no event without its kind");
}

}  // namespace

int main() {
    surgery();
    demonstration();
    force_loop();
    std::printf("%d failures\n", failures);
    return failures == 0 ? 0 : 1;
}
