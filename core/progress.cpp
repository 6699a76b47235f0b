#include "core/progress.h"

#include <unistd.h>

#include <cstdio>

namespace dvso {

ProgressBar::ProgressBar(std::string label, long total)
    : label_(std::move(label)), total_(total > 0 ? total : 1), tty_(::isatty(STDERR_FILENO) != 0) {
  start_ = std::chrono::steady_clock::now();
  last_draw_ = start_ - std::chrono::seconds(1);
}

ProgressBar::~ProgressBar() {
  if (!finished_ && done_ > 0) Finish();
}

void ProgressBar::Update(long done, const std::string& status) {
  done_ = done;
  status_ = status;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100) && done_ < total_) return;
  last_draw_ = now;
  Draw(false);
}

void ProgressBar::Finish(const std::string& status) {
  if (finished_) return;
  if (!status.empty()) status_ = status;
  done_ = std::max(done_, 0L);
  finished_ = true;
  Draw(true);
}

void ProgressBar::Draw(bool final_line) {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double fraction = std::min(1.0, static_cast<double>(done_) / total_);
  const double rate = elapsed > 0 ? done_ / elapsed : 0.0;
  const double eta = rate > 0 ? (total_ - done_) / rate : 0.0;
  if (tty_) {
    const int width = 30;
    const int filled = static_cast<int>(fraction * width);
    std::string bar(filled, '#');
    bar.append(width - filled, '.');
    std::fprintf(stderr, "\r%s [%s] %ld/%ld %.1f/s eta %.0fs %s\033[K", label_.c_str(), bar.c_str(), done_,
                 total_, rate, eta, status_.c_str());
    if (final_line) std::fprintf(stderr, "\n");
  } else {
    const int percent = static_cast<int>(fraction * 100);
    if (final_line || percent >= last_logged_percent_ + 10) {
      last_logged_percent_ = percent;
      std::fprintf(stderr, "%s: %ld/%ld (%d%%) %.1f/s %s\n", label_.c_str(), done_, total_, percent, rate,
                   status_.c_str());
    }
  }
  std::fflush(stderr);
}

}  // namespace dvso
