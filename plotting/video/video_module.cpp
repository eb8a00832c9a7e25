// The video writer, a module loaded only when a video is written (plotting/canvas.cpp, write_video):
// OpenCV's videoio pulls in FFmpeg, GStreamer and some hundred shared libraries whose loading cost
// every flexfarm command ~0.2 s at start-up while it was linked into the program.
#include <opencv2/videoio.hpp>

#include <cstdio>
#include <functional>

// Writes `frames` frames, frame(k) each (8-bit BGR of the given size), to `path` with the codec
// `fourcc` through the videoio backend `api`. 1: written; 0: the backend or codec could not be
// opened or failed (OpenCV's message, if any, in `why`). What frame() throws passes through.
extern "C" int ff_write_video(const char* path, int api, int fourcc, double fps, int width, int height, int frames,
                              const std::function<cv::Mat(int)>* frame, char* why, unsigned long why_size) {
  cv::VideoWriter w;
  try {
    if (!w.open(path, api, fourcc, fps, cv::Size(width, height), true)) return 0;
    for (int k = 0; k < frames; ++k) w.write((*frame)(k));
    w.release();
    return 1;
  } catch (const cv::Exception& e) {
    w.release();
    std::snprintf(why, why_size, "%s", e.what());
    return 0;
  } catch (...) {
    w.release();
    throw;
  }
}
