#include "vo/system/sequence_runner.h"

#include <algorithm>
#include <chrono>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/progress.h"
#include "core/trajectory.h"
#include "vo/system/output_writers.h"
#include "vo/system/system.h"

namespace dvso::vo {

namespace {
// Set by SIGINT / SIGTERM while a run that asked for it is in progress. The first signal asks the run
// to stop and write what it has. Copies of it within kRepeatedSignalWindowSeconds (whole seconds of the
// monotonic clock: 1-2 s) are the same request
// (GNU timeout, and a terminal, signal the process and then its group); a signal after that ends the
// process at once (default action), for a long finish the user no longer wants. What that kill leaves
// is not a finished run: no INTERRUPTED marker, possibly temporary files (*.tmp-writing*,
// run_log.csv.partial) and a new run log beside the old trajectory; every file in place is complete
// (atomic writes). clock_gettime, signal and raise are async-signal-safe (POSIX).
constexpr long kRepeatedSignalWindowSeconds = 2;
volatile std::sig_atomic_t g_interrupt_requested = 0;
volatile std::sig_atomic_t g_first_signal_second = 0;  // CLOCK_MONOTONIC seconds of the first signal
extern "C" void RequestInterrupt(int signal_number) {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  if (!g_interrupt_requested) {
    g_first_signal_second = static_cast<std::sig_atomic_t>(now.tv_sec);
    g_interrupt_requested = 1;
    return;
  }
  if (now.tv_sec - g_first_signal_second < kRepeatedSignalWindowSeconds) return;
  std::signal(signal_number, SIG_DFL);
  std::raise(signal_number);
}

// Installs the handlers for the lifetime of a run and restores the old ones.
class InterruptScope {
 public:
  explicit InterruptScope(bool active) : active_(active) {
    if (!active_) return;
    g_interrupt_requested = 0;
    old_int_ = std::signal(SIGINT, RequestInterrupt);
    old_term_ = std::signal(SIGTERM, RequestInterrupt);
  }
  ~InterruptScope() {
    if (!active_) return;
    std::signal(SIGINT, old_int_);
    std::signal(SIGTERM, old_term_);
  }
  bool requested() const { return active_ && g_interrupt_requested != 0; }

 private:
  bool active_;
  void (*old_int_)(int) = SIG_DFL;
  void (*old_term_)(int) = SIG_DFL;
};

// Frame `index`, or nothing when its images cannot be read: a damaged image
// must not throw away the run before it, so it is warned about and skipped
// (the caller counts it as lost). `strict` rethrows instead.
std::optional<StereoFrame> ReadFrameOrWarn(const SequenceReader& sequence, int index, const SequenceReadOptions& read,
                                           bool strict) {
  try {
    return sequence.Read(index, read);
  } catch (const Error& e) {
    if (strict) throw;
    std::cerr << "\ndvso: warning: frame " << index << " skipped (counted as lost): " << e.what() << std::endl;
    return std::nullopt;
  }
}
}  // namespace

void SequenceRunOptions::Check() const {
  Require(first >= 0, "--first must be >= 0");
  Require(count == -1 || count >= 1, "--count must be >= 1 (or -1 for all)");
}

SequenceRunSummary RunOdometryOnSequence(const SequenceReader& sequence, const OdometryOptions& options,
                                         OdometryMode mode, const std::string& out_dir,
                                         const SequenceRunOptions& run) {
  run.Check();
  options.Check();
  const ModeCapabilities capabilities = CapabilitiesOf(mode);
  if (capabilities.has_right_image) {
    Require(sequence.is_stereo(),
            sequence.root() + ": this mode needs a stereo sequence: " + sequence.NotStereoReason());
  }
  Require(run.first < sequence.size(), "--first " + std::to_string(run.first) + " is beyond the sequence (" +
                                           std::to_string(sequence.size()) + " frames)");
  const int end = RunEndFrame(sequence.size(), run.first, run.count);
  if (const std::string w = CountPastEndWarning(sequence.size(), run.first, run.count); !w.empty()) std::cerr << w << "\n";
  EnsureDirectory(out_dir);
  // Checked before the run: the log and point cloud are finished (renamed into place) before the
  // trajectories are written, so a trajectory path that cannot be a file would fail the run only after
  // its log had replaced an earlier run's.
  for (const char* name : {"trajectory.txt", "trajectory_tum.txt", "config.yaml", "run_log.csv", "points.ply"}) {
    const std::string path = JoinPath(out_dir, name);
    RequireFile(!std::filesystem::is_directory(path), path, "is a folder: the run cannot write its output there");
  }

  System system(options, sequence.camera(), mode, run.predictions);
  TrajectoryRecorder recorder;
  RunLogWriter log(JoinPath(out_dir, "run_log.csv"));
  std::unique_ptr<PlyPointWriter> ply;
  system.AddObserver(&recorder);
  system.AddObserver(&log);
  if (run.write_ply) {
    ply = std::make_unique<PlyPointWriter>(JoinPath(out_dir, "points.ply"));
    system.AddObserver(ply.get());
  }
  for (OdometryObserver* o : run.extra_observers) system.AddObserver(o);
  SequenceRunSummary summary;
  std::unique_ptr<ProgressBar> bar;
  if (run.progress) bar = std::make_unique<ProgressBar>("odometry " + ToString(mode), end - run.first);
  SequenceReadOptions read;
  read.load_right = capabilities.has_right_image;  // DVSO is monocular: an existing right image is not read
  double total_ms = 0;
  const auto loop_start = std::chrono::steady_clock::now();
  const InterruptScope interrupt(run.stop_on_interrupt);
  for (int i = run.first; i < end; ++i) {
    if (interrupt.requested()) {
      summary.interrupted = true;
      break;
    }
    const std::optional<StereoFrame> frame = ReadFrameOrWarn(sequence, i, read, run.strict);
    FrameEvent ev;
    if (frame) {
      ev = system.ProcessFrame(i, frame->timestamp, frame->left, frame->right);
    } else {
      ++summary.unreadable;
      ev = system.ReportUnreadableFrame(i, sequence.timestamps().at(i));
    }
    total_ms += ev.total_ms;
    summary.max_ms = std::max(summary.max_ms, ev.total_ms);
    ++summary.frames;
    if (bar) {
      std::ostringstream status;
      status << ToString(ev.status) << " kf " << system.num_keyframes_total() << " pts " << ev.active_points << " "
             << static_cast<int>(total_ms / summary.frames) << " ms/f";
      bar->Update(i - run.first + 1, status.str());
    }
  }
  RequireFile(summary.frames == 0 || summary.unreadable < summary.frames, sequence.root(),
              "none of the " + std::to_string(summary.frames) + " frames could be read (warnings above)");
  system.Finish();
  summary.wall_ms = summary.frames > 0 ? std::chrono::duration<double, std::milli>(
                                             std::chrono::steady_clock::now() - loop_start).count() / summary.frames
                                       : 0;
  if (bar) bar->Finish();
  const Trajectory trajectory = recorder.Resolve();
  WriteKittiTrajectory(JoinPath(out_dir, "trajectory.txt"), trajectory);
  WriteTumTrajectory(JoinPath(out_dir, "trajectory_tum.txt"), trajectory);
  // Written last: a run that failed leaves neither log nor config behind.
  SaveOdometryOptions(JoinPath(out_dir, "config.yaml"), system.options());
  // The marker of an earlier interrupted run goes only now that this run's files replace its partial ones: a
  // run that fails before this point leaves those files marked.
  if (summary.interrupted) {
    WriteStreamAtomically(JoinPath(out_dir, "INTERRUPTED"), [&](std::ostream& marker) {
      marker << "interrupted after " << summary.frames << " of " << end - run.first
             << " frames; trajectory.txt, trajectory_tum.txt and run_log.csv hold those frames\n";
    });
  } else {
    std::filesystem::remove(JoinPath(out_dir, "INTERRUPTED"));
  }
  // An earlier run's point cloud beside this run's trajectory would pass for this run's.
  if (!run.write_ply) std::filesystem::remove(JoinPath(out_dir, "points.ply"));
  summary.keyframes = system.num_keyframes_total();
  summary.lost = recorder.CountStatus(FrameStatus::kLost) + recorder.CountStatus(FrameStatus::kUnreadable);
  summary.initializing = recorder.CountStatus(FrameStatus::kInitializing);
  summary.tracked = recorder.CountStatus(FrameStatus::kTracked) + recorder.CountStatus(FrameStatus::kKeyframe);
  summary.resets = system.num_resets();
  summary.mean_ms = summary.frames > 0 ? total_ms / summary.frames : 0;
  summary.ply_points = ply ? ply->num_points() : 0;
  return summary;
}

}  // namespace dvso::vo
