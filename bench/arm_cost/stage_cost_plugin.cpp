// A qemu TCG plugin for qemu-user (Debian's qemu-user package, qemu 7.2, plugin API version
// 1): counts the ARM instructions each guest thread executes, attributed to the cost stage
// the thread last declared with mark_cost_stage() (include/rgbd_odometry/core/cost_stage.hpp).
// At exit it writes one line per stage to the file named by its argument out=FILE:
//   STAGE_NAME INSTRUCTIONS ENTRIES
// ENTRIES counts the marks that entered the stage (frames for mask, pairs for match).
// Then, per frame, one line "frame_start I_0 ... I_14": the stages' instructions counted so far
// on the thread that processes the frames, at its mark that enters the mask stage (a frame's
// first stage); and a last such line at exit. Consecutive differences are what each frame cost
// that thread, stage by stage. Work on other threads (the reader's conversion) is left out: it
// would fall into whichever frame it ran beside. So a frame's stages must run on one thread:
// arm_cost.cmake runs one processing thread (with two, estimation would count as elsewhere).
//
// Declarations: the few parts of qemu's plugin API used here, written from its documented
// signatures (qemu-plugin.h of qemu 7.2; no qemu headers are packaged in Debian).
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <vector>

#include "rgbd_odometry/core/cost_stage.hpp"

extern "C" {
typedef std::uint64_t qemu_plugin_id_t;
struct qemu_plugin_tb;
struct qemu_info_t;
enum qemu_plugin_cb_flags { QEMU_PLUGIN_CB_NO_REGS, QEMU_PLUGIN_CB_R_REGS, QEMU_PLUGIN_CB_RW_REGS };
typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t, struct qemu_plugin_tb*);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void* userdata);
typedef void (*qemu_plugin_vcpu_simple_cb_t)(qemu_plugin_id_t, unsigned int vcpu_index);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t, void* userdata);
typedef void (*qemu_plugin_vcpu_syscall_cb_t)(qemu_plugin_id_t, unsigned int vcpu_index, std::int64_t num,
                                              std::uint64_t a1, std::uint64_t a2, std::uint64_t a3, std::uint64_t a4,
                                              std::uint64_t a5, std::uint64_t a6, std::uint64_t a7, std::uint64_t a8);
void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t, qemu_plugin_vcpu_tb_trans_cb_t);
void qemu_plugin_register_vcpu_tb_exec_cb(struct qemu_plugin_tb*, qemu_plugin_vcpu_udata_cb_t, enum qemu_plugin_cb_flags,
                                          void* userdata);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb*);
void qemu_plugin_register_vcpu_init_cb(qemu_plugin_id_t, qemu_plugin_vcpu_simple_cb_t);
void qemu_plugin_register_vcpu_syscall_cb(qemu_plugin_id_t, qemu_plugin_vcpu_syscall_cb_t);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t, qemu_plugin_udata_cb_t, void* userdata);
}

namespace {

using rgbdo::kCostStageCount;

// qemu-user gives each guest thread a vCPU, numbered from 0 and reused after a thread ends.
// The program runs a handful of threads; beyond kMaxThreads they share the last slot.
constexpr unsigned kMaxThreads = 64;
constexpr long kGetpidArm = 20;  // __NR_getpid on ARM EABI: the marker's system call

struct ThreadCount {
  std::atomic<std::uint32_t> stage{0};
  std::atomic<std::uint64_t> instructions[kCostStageCount] = {};
  std::atomic<std::uint64_t> entries[kCostStageCount] = {};
};
ThreadCount g_threads[kMaxThreads];
const char* g_out = "stage_cost.txt";
std::mutex g_frame_starts_mutex;
using StageTotals = std::array<std::uint64_t, kCostStageCount>;
std::vector<StageTotals> g_frame_starts;  // the processing thread's counts at each frame's first mark
unsigned g_frame_vcpu = 0;                 // the processing thread's vCPU

ThreadCount& thread_count(unsigned vcpu) { return g_threads[vcpu < kMaxThreads ? vcpu : kMaxThreads - 1]; }

// Each translation block adds its length to the executing thread's current stage. (An inline
// add cannot follow the stage: its target address is fixed when the block is translated.)
void on_block(unsigned vcpu, void* n_insns) {
  ThreadCount& t = thread_count(vcpu);
  t.instructions[t.stage.load(std::memory_order_relaxed)].fetch_add(reinterpret_cast<std::uintptr_t>(n_insns),
                                                                     std::memory_order_relaxed);
}

StageTotals stage_totals(unsigned vcpu) {
  StageTotals totals{};
  const ThreadCount& t = thread_count(vcpu);
  for (std::size_t s = 0; s < kCostStageCount; ++s) totals[s] = t.instructions[s].load(std::memory_order_relaxed);
  return totals;
}

void on_translate(qemu_plugin_id_t, struct qemu_plugin_tb* tb) {
  const auto n = static_cast<std::uintptr_t>(qemu_plugin_tb_n_insns(tb));
  qemu_plugin_register_vcpu_tb_exec_cb(tb, on_block, QEMU_PLUGIN_CB_NO_REGS, reinterpret_cast<void*>(n));
}

void on_thread_start(qemu_plugin_id_t, unsigned vcpu) { thread_count(vcpu).stage = 0; }

void on_syscall(qemu_plugin_id_t, unsigned vcpu, std::int64_t num, std::uint64_t a1, std::uint64_t a2, std::uint64_t,
                std::uint64_t, std::uint64_t, std::uint64_t, std::uint64_t, std::uint64_t) {
  if (num != kGetpidArm || static_cast<std::uint32_t>(a1) != rgbdo::kCostMarkerMagic) return;
  const auto stage = static_cast<std::uint32_t>(a2);
  if (stage >= kCostStageCount) return;
  ThreadCount& t = thread_count(vcpu);
  t.stage = stage;
  t.entries[stage].fetch_add(1, std::memory_order_relaxed);
  if (stage == static_cast<std::uint32_t>(rgbdo::CostStage::Mask)) {
    const std::lock_guard<std::mutex> lock(g_frame_starts_mutex);
    g_frame_vcpu = vcpu;
    g_frame_starts.push_back(stage_totals(vcpu));
  }
}

void on_exit(qemu_plugin_id_t, void*) {
  std::FILE* f = std::fopen(g_out, "w");
  if (f == nullptr) {
    std::fprintf(stderr, "stage_cost_plugin: cannot write %s\n", g_out);
    return;
  }
  for (std::size_t s = 0; s < kCostStageCount; ++s) {
    std::uint64_t instructions = 0, entries = 0;
    for (const ThreadCount& t : g_threads) {
      instructions += t.instructions[s].load();
      entries += t.entries[s].load();
    }
    std::fprintf(f, "%s %llu %llu\n", rgbdo::kCostStageNames[s], static_cast<unsigned long long>(instructions),
                 static_cast<unsigned long long>(entries));
  }
  const std::lock_guard<std::mutex> lock(g_frame_starts_mutex);
  g_frame_starts.push_back(stage_totals(g_frame_vcpu));
  for (const StageTotals& totals : g_frame_starts) {
    std::fprintf(f, "frame_start");
    for (const std::uint64_t n : totals) std::fprintf(f, " %llu", static_cast<unsigned long long>(n));
    std::fprintf(f, "\n");
  }
  std::fclose(f);
}

}  // namespace

extern "C" {
__attribute__((visibility("default"))) int qemu_plugin_version = 1;

__attribute__((visibility("default"))) int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t*, int argc,
                                                                char** argv) {
  for (int i = 0; i < argc; ++i)
    if (std::strncmp(argv[i], "out=", 4) == 0) g_out = argv[i] + 4;
  qemu_plugin_register_vcpu_init_cb(id, on_thread_start);
  qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
  qemu_plugin_register_vcpu_syscall_cb(id, on_syscall);
  qemu_plugin_register_atexit_cb(id, on_exit, nullptr);
  return 0;
}
}
