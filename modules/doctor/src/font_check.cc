#include "bricklayer/doctor/font_check.h"

#include <SDL_ttf.h>

#include <string>

namespace bricklayer::doctor {

CheckResult check_font(const HostPlan& plan) {
  const std::string name = "fonts";
  if (!plan.projection) return CheckResult::ok(name, "profile " + plan.profile + " runs no projection");
  if (!TTF_WasInit() && TTF_Init() != 0) return CheckResult::failed(name, std::string("SDL_ttf: ") + TTF_GetError(), "reinstall libsdl2-ttf-2.0-0");
  TTF_Font* font = TTF_OpenFont(plan.font.c_str(), 24);
  if (!font)
    return CheckResult::failed(name, "cannot load " + plan.font + " (" + TTF_GetError() + "): projection would stop",
                               "sudo apt-get install fonts-dejavu-core, or give projection --font FILE.ttf");
  const char* family = TTF_FontFaceFamilyName(font);
  const char* style = TTF_FontFaceStyleName(font);
  const std::string what = std::string(family ? family : "?") + " " + (style ? style : "");
  TTF_CloseFont(font);
  return CheckResult::ok(name, plan.font + " (" + what + ")");
}

}  // namespace bricklayer::doctor
