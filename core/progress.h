// A terminal progress bar for long work (rendering, odometry, training).
// Draws on stderr, redraws at most ~10 times a second, and prints plain
// periodic lines instead when stderr is not a terminal (CI logs stay readable).
#pragma once

#include <chrono>
#include <string>

namespace dvso {

class ProgressBar {
 public:
  ProgressBar(std::string label, long total);
  ~ProgressBar();
  // Sets the number of finished items; `status` is shown after the bar (e.g. loss terms).
  void Update(long done, const std::string& status = "");
  void Finish(const std::string& status = "");

 private:
  void Draw(bool final_line);
  std::string label_;
  long total_;
  long done_ = 0;
  std::string status_;
  bool tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
  int last_logged_percent_ = -10;
};

}  // namespace dvso
