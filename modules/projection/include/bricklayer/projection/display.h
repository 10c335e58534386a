// The SDL window (or offscreen surface) the projector shows. Everything is drawn into a target
// texture of the projector's size, which is then stretched over the window and presented; captures
// (snapshots, projector_state_t) read that texture, so they are exactly the presented frame at the
// projector's resolution whatever the window size.
#pragma once

#include <SDL.h>

#include <string>

#include <opencv2/core.hpp>

namespace bricklayer::projection {

enum class DisplayMode {
  kFullscreen,  // borderless fullscreen on display i (SDL_WINDOW_FULLSCREEN_DESKTOP)
  kWindow,      // a plain window, for development
  kHeadless,    // SDL's offscreen video driver (set by Display), software rendering
};

struct DisplayOptions {
  DisplayMode mode = DisplayMode::kHeadless;
  int display_index = 0;
  int width = 1024;   // projector pixels
  int height = 768;
  bool vsync = true;  // ignored headless
  // SDL render driver for a real screen ("" = SDL's choice, "software", "opengl", ...). Headless always
  // uses "software". Under Xvfb "software" is far cheaper than OpenGL through Mesa's llvmpipe.
  std::string render_driver;
  std::string title = "bricklayer-projection";
};

class Display {
 public:
  // Initialises SDL video (headless: sets SDL_VIDEODRIVER=offscreen first). Throws
  // std::runtime_error with SDL's message when the window or renderer cannot be created.
  explicit Display(const DisplayOptions& options);
  ~Display();
  Display(const Display&) = delete;
  Display& operator=(const Display&) = delete;

  SDL_Renderer* renderer() { return renderer_; }
  int width() const { return options_.width; }
  int height() const { return options_.height; }
  DisplayMode mode() const { return options_.mode; }

  // Starts a frame: subsequent drawing goes into the projector-size frame texture.
  void begin_frame();
  // Stretches the frame over the window and presents it.
  void present();
  // The frame last drawn, BGR CV_8UC3 at projector size (SDL_RenderReadPixels on the frame texture).
  cv::Mat read_frame();

 private:
  DisplayOptions options_;
  SDL_Window* window_ = nullptr;
  SDL_Renderer* renderer_ = nullptr;
  SDL_Texture* frame_ = nullptr;
};

}  // namespace bricklayer::projection
