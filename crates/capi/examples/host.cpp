// A host's use of tissue.h: plan the Table 2 case with a progress bar (Ctrl-C-free: the
// callback could return 1 to cancel), then press a probe into the shipped appendix while a
// haptic thread asks for the force at 1 kHz. Build it with the CMakeLists.txt beside it, or:
//
//   cargo build -p tissue-capi --release
//   c++ -std=c++17 -O2 crates/capi/examples/host.cpp -I crates/capi/include
//       target/release/libtissue.a -lpthread -ldl -lm -o host   (one line)
#include <atomic>
#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

#include "tissue.h"

static bool ok(tissue_status s, const char* what) {
    if (s == TISSUE_OK) return true;
    std::string message(tissue_last_error(nullptr, 0), '\0');
    if (!message.empty()) {
        tissue_last_error(message.data(), message.size());
        message.pop_back();
    }
    std::fprintf(stderr, "%s failed (%d): %s\n", what, static_cast<int>(s), message.c_str());
    return false;
}

static int show_progress(const tissue_progress* p, void*) {
    std::printf("\rstep %llu of at most %llu, settled %3.0f %%, %.1f s",
                static_cast<unsigned long long>(p->step),
                static_cast<unsigned long long>(p->max_steps), 100.0 * p->settle, p->elapsed_s);
    std::fflush(stdout);
    return 0;  // non-zero cancels
}

int main() {
    // --- Planning.
    tissue_patient* patient = nullptr;
    tissue_plan_options options;
    tissue_job* job = nullptr;
    if (!ok(tissue_patient_shipped(TISSUE_PATIENT_TABLE2, &patient), "patient") ||
        !ok(tissue_plan_options_default(&options), "options")) {
        return 1;
    }
    options.volume_cm3 = 100.0;
    const bool planned =
        ok(tissue_plan_run(patient, &options, show_progress, nullptr, &job), "plan");
    std::printf("\n");
    if (planned) {
        tissue_plan_result r{};
        if (ok(tissue_job_result(job, &r), "result")) {
            std::printf("gain %.2f cm2, volume difference %.2f cm3, %llu steps\n",
                        r.area_gain_cm2, r.volume_difference_cm3,
                        static_cast<unsigned long long>(r.steps));
        }
    }
    tissue_job_free(job);
    tissue_patient_free(patient);

    // --- Training: physics at 100 Hz on this thread, haptics at 1 kHz on another.
    tissue_body* body = nullptr;
    if (!ok(tissue_body_new_shipped(TISSUE_ORGAN_APPENDIX, &body), "body")) return 1;
    const float tip[3] = {0, 0, 0}, shaft[3] = {0, 3, 0};
    tissue_pose pose{{0, 0, 0, 1}, {1.5f, 2.6f, 0}};
    uint32_t probe = 0;
    if (!ok(tissue_body_add_capsule(body, tip, shaft, 0.3f, &pose, &probe), "probe")) return 1;
    std::atomic<bool> stop{false};
    std::thread haptic([&] {
        auto next = std::chrono::steady_clock::now();
        for (int tick = 0; !stop; ++tick) {
            // A device would give the pose; here the probe goes down at 1 cm/s to y = 1.9 cm
            // (its tip 0.4 cm into the organ).
            const float y = 2.6f - 0.001f * static_cast<float>(tick);
            tissue_pose device{{0, 0, 0, 1}, {1.5f, y > 1.9f ? y : 1.9f, 0}};
            float force[3];
            tissue_tool_set_pose(body, probe, &device);
            tissue_tool_force(body, probe, force, nullptr);
            if (tick % 100 == 0) std::printf("haptic: %.3f N up\n", force[1]);
            next += std::chrono::milliseconds(1);
            std::this_thread::sleep_until(next);
        }
    });
    auto next = std::chrono::steady_clock::now();
    for (int step = 0; step < 100; ++step) {
        if (!ok(tissue_body_step(body, nullptr), "step")) break;
        next += std::chrono::milliseconds(10);
        std::this_thread::sleep_until(next);
    }
    stop = true;
    haptic.join();  // no call may use the body once it is freed
    tissue_body_free(body);
    return 0;
}
