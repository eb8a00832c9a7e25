// Progress of a long run on stderr: an updating bar with rate and ETA on a terminal, plain lines
// (at most every few seconds, and the last) otherwise.
#pragma once

#include <string>

namespace ff {

class Progress {
 public:
  Progress(std::string what, bool terminal);
  // done of total finished after `seconds`; `fresh` of them computed now (the rate counts those).
  void update(int done, int total, int fresh, double seconds);
  void finish();

 private:
  std::string what_;
  bool terminal_;
  double last_print_ = -1e9;
  bool open_line_ = false;
};

// Whether stderr is a terminal.
bool stderr_is_terminal();

}  // namespace ff
