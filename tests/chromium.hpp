// Pages in headless Chromium (Debian's chromium, installed by scripts/bootstrap; or $FLEXFARM_CHROMIUM),
// for the tests of the pages flexfarm writes (the 3-D viewer, the run report): each page's DOM once
// loaded and its screenshot, kept in the tests' artefacts/ folder.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace ff::test {

// Chromium: $FLEXFARM_CHROMIUM or Debian's /usr/bin/chromium.
inline std::string chromium() {
  const char* env = std::getenv("FLEXFARM_CHROMIUM");
  return env && *env ? env : "/usr/bin/chromium";
}

// The tests' artefacts folder (the build's tests/artefacts under ctest: the working directory).
inline std::filesystem::path artefact(const std::string& name) {
  const std::filesystem::path dir = std::filesystem::current_path() / "artefacts";
  std::filesystem::create_directories(dir);
  return dir / name;
}

struct BrowserPage {
  std::string url;         // file://... (with a #hash)
  std::string screenshot;  // its file name in `work` and in artefacts/
};

// Each page loaded in headless Chromium at `width` x `height` (software WebGL: SwiftShader), side by side
// (most of a run is Chromium starting and stopping), given `budget_ms` of virtual time: their DOMs, in
// order ("" for one that failed, which fails the test). The screenshots go to `work` and are copied to
// artefacts/. Fails the test when Chromium is missing.
inline std::vector<std::string> load_in_chromium(const std::vector<BrowserPage>& pages, const std::filesystem::path& work,
                                                 int width, int height, int budget_ms = 1000) {
  const std::string browser = chromium();
  if (::access(browser.c_str(), X_OK) != 0) {
    ADD_FAILURE() << "no Chromium at " << browser << " (or set FLEXFARM_CHROMIUM): run scripts/bootstrap, "
                  << "which installs Debian's chromium for the browser tests";
    return std::vector<std::string>(pages.size());
  }
  std::vector<std::string> cmds, doms(pages.size());
  std::vector<FILE*> pipes;
  for (std::size_t i = 0; i < pages.size(); ++i) {
    cmds.push_back("timeout 60 '" + browser + "' --headless=new --no-sandbox --disable-gpu --use-angle=swiftshader "
                   "--enable-unsafe-swiftshader --window-size=" + std::to_string(width) + "," + std::to_string(height) +
                   " --hide-scrollbars --user-data-dir='" + (work / ("profile" + std::to_string(i))).string() +
                   "' --virtual-time-budget=" + std::to_string(budget_ms) + " --screenshot='" +
                   (work / pages[i].screenshot).string() + "' --dump-dom '" + pages[i].url + "' 2>/dev/null");
    pipes.push_back(::popen(cmds.back().c_str(), "r"));
    if (!pipes.back()) throw std::runtime_error("cannot run " + browser);
  }
  for (std::size_t i = 0; i < pages.size(); ++i) {
    char buf[4096];
    for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, pipes[i])) > 0;) doms[i].append(buf, n);
    const int status = ::pclose(pipes[i]);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << cmds[i] << "\nexit status " << status;
    const std::filesystem::path shot = work / pages[i].screenshot;
    if (!std::filesystem::exists(shot)) {
      ADD_FAILURE() << "no screenshot from: " << cmds[i];
      doms[i].clear();
      continue;
    }
    std::filesystem::copy_file(shot, artefact(pages[i].screenshot), std::filesystem::copy_options::overwrite_existing);
    std::cout << "screenshot of " << pages[i].url << ": " << artefact(pages[i].screenshot).string() << "\n";
  }
  return doms;
}

}  // namespace ff::test
