#include "jobs/progress.hpp"

#include <unistd.h>

#include <cstdio>

#include "common/text.hpp"

namespace ff {

bool stderr_is_terminal() { return isatty(fileno(stderr)) != 0; }

Progress::Progress(std::string what, bool terminal) : what_(terminal_safe(what)), terminal_(terminal) {}

namespace {
std::string clock_text(double s) {
  char buf[32];
  if (s < 60) std::snprintf(buf, sizeof buf, "%.0fs", s);
  else if (s < 3600) std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s) / 60, static_cast<int>(s) % 60);
  else std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s) / 3600, static_cast<int>(s) / 60 % 60);
  return buf;
}
}  // namespace

void Progress::update(int done, int total, int fresh, double seconds) {
  const bool last = done >= total;
  if (!terminal_ && !last && seconds - last_print_ < 5.0) return;
  if (terminal_ && !last && seconds - last_print_ < 0.1) return;
  last_print_ = seconds;
  const double rate = seconds > 0 ? fresh / seconds : 0.0;
  const double eta = rate > 0 ? (total - done) / rate : 0.0;
  const double frac = total > 0 ? static_cast<double>(done) / total : 1.0;
  char tail[128];
  std::snprintf(tail, sizeof tail, "%d/%d variants  %.1f/s  elapsed %s  ETA %s", done, total, rate,
                clock_text(seconds).c_str(), rate > 0 ? clock_text(eta).c_str() : "-");
  if (terminal_) {
    constexpr int kWidth = 30;
    const int fill = static_cast<int>(frac * kWidth);
    std::string bar(fill, '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r%s [%s] %3.0f%%  %s ", what_.c_str(), bar.c_str(), 100 * frac, tail);
    open_line_ = true;
  } else {
    std::fprintf(stderr, "%s: %3.0f%%  %s\n", what_.c_str(), 100 * frac, tail);
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (open_line_) std::fprintf(stderr, "\n");
  open_line_ = false;
}

}  // namespace ff
