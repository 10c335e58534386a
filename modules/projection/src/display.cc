#include "bricklayer/projection/display.h"

#include <cstdlib>
#include <stdexcept>
#include <string>

#include "bricklayer/common/log.h"

namespace bricklayer::projection {

namespace {
std::string sdl_error(const std::string& what) { return what + ": " + SDL_GetError(); }
}  // namespace

Display::Display(const DisplayOptions& options) : options_(options) {
  if (options.width < 16 || options.height < 16 || options.width > 16384 || options.height > 16384)
    throw std::invalid_argument("projector size " + std::to_string(options.width) + "x" +
                                std::to_string(options.height) + " is out of range (16..16384)");
  if (options.mode == DisplayMode::kHeadless) {
    setenv("SDL_VIDEODRIVER", "offscreen", 1);
    SDL_SetHint(SDL_HINT_RENDER_DRIVER, "software");
    // Without this the offscreen driver emulates its framebuffer through OpenGL (Mesa's llvmpipe):
    // measured 20 ms a frame instead of ~1 ms.
    SDL_SetHint(SDL_HINT_FRAMEBUFFER_ACCELERATION, "0");
  } else if (!options.render_driver.empty()) {
    SDL_SetHint(SDL_HINT_RENDER_DRIVER, options.render_driver.c_str());
    if (options.render_driver == "software") SDL_SetHint(SDL_HINT_FRAMEBUFFER_ACCELERATION, "0");
  }
  if (SDL_InitSubSystem(SDL_INIT_VIDEO) != 0) throw std::runtime_error(sdl_error("cannot initialise SDL video"));

  Uint32 flags = SDL_WINDOW_SHOWN;
  int x = SDL_WINDOWPOS_UNDEFINED, y = SDL_WINDOWPOS_UNDEFINED;
  switch (options.mode) {
    case DisplayMode::kFullscreen: {
      const int displays = SDL_GetNumVideoDisplays();
      if (options.display_index < 0 || options.display_index >= displays) {
        SDL_QuitSubSystem(SDL_INIT_VIDEO);
        throw std::runtime_error("display " + std::to_string(options.display_index) + " does not exist (" +
                                 std::to_string(displays) + " display(s) found)");
      }
      x = y = static_cast<int>(SDL_WINDOWPOS_UNDEFINED_DISPLAY(options.display_index));
      flags |= SDL_WINDOW_FULLSCREEN_DESKTOP | SDL_WINDOW_BORDERLESS;
      break;
    }
    case DisplayMode::kWindow: flags |= SDL_WINDOW_RESIZABLE; break;
    case DisplayMode::kHeadless: flags = SDL_WINDOW_HIDDEN; break;
  }
  window_ = SDL_CreateWindow(options.title.c_str(), x, y, options.width, options.height, flags);
  if (!window_) {
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    throw std::runtime_error(sdl_error("cannot create the projector window"));
  }
  Uint32 renderer_flags = SDL_RENDERER_TARGETTEXTURE;
  if (options.mode != DisplayMode::kHeadless && options.vsync) renderer_flags |= SDL_RENDERER_PRESENTVSYNC;
  renderer_ = SDL_CreateRenderer(window_, -1, renderer_flags);
  if (!renderer_) renderer_ = SDL_CreateRenderer(window_, -1, SDL_RENDERER_SOFTWARE | SDL_RENDERER_TARGETTEXTURE);
  if (!renderer_) {
    std::string message = sdl_error("cannot create a renderer");
    SDL_DestroyWindow(window_);
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    throw std::runtime_error(message);
  }
  frame_ = SDL_CreateTexture(renderer_, SDL_PIXELFORMAT_ARGB8888, SDL_TEXTUREACCESS_TARGET, options.width,
                             options.height);
  if (!frame_) {
    std::string message = sdl_error("cannot create the frame texture");
    SDL_DestroyRenderer(renderer_);
    SDL_DestroyWindow(window_);
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    throw std::runtime_error(message);
  }
  SDL_RendererInfo info{};
  SDL_GetRendererInfo(renderer_, &info);
  log::info("display: ", SDL_GetCurrentVideoDriver(), " video, ", info.name, " renderer, projector ", options.width,
            "x", options.height);
  if (options.mode != DisplayMode::kHeadless) SDL_ShowCursor(SDL_DISABLE);
}

Display::~Display() {
  if (frame_) SDL_DestroyTexture(frame_);
  if (renderer_) SDL_DestroyRenderer(renderer_);
  if (window_) SDL_DestroyWindow(window_);
  SDL_QuitSubSystem(SDL_INIT_VIDEO);
}

void Display::begin_frame() {
  SDL_SetRenderTarget(renderer_, frame_);
  SDL_SetRenderDrawBlendMode(renderer_, SDL_BLENDMODE_NONE);
  SDL_SetRenderDrawColor(renderer_, 0, 0, 0, 255);
  SDL_RenderClear(renderer_);
}

void Display::present() {
  SDL_SetRenderTarget(renderer_, nullptr);
  SDL_SetRenderDrawColor(renderer_, 0, 0, 0, 255);
  SDL_RenderClear(renderer_);
  SDL_RenderCopy(renderer_, frame_, nullptr, nullptr);
  SDL_RenderPresent(renderer_);
}

cv::Mat Display::read_frame() {
  cv::Mat bgr(options_.height, options_.width, CV_8UC3);
  SDL_SetRenderTarget(renderer_, frame_);
  if (SDL_RenderReadPixels(renderer_, nullptr, SDL_PIXELFORMAT_BGR24, bgr.data, static_cast<int>(bgr.step)) != 0)
    throw std::runtime_error(sdl_error("cannot read the frame's pixels"));
  return bgr;
}

}  // namespace bricklayer::projection
