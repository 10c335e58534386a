#include "bricklayer/projection/knife_edge_look.h"

#include <cmath>
#include <cstdio>

namespace bricklayer::projection {

namespace {
constexpr double kCapMm = 3.75;  // prediction's largest margin (0.05 block lengths of 75 mm)
}

std::string margin_text(double margin_mm) {
  if (!std::isfinite(margin_mm)) return "";
  const double a = std::abs(margin_mm);
  if (a < 0.05) return "on the edge";
  char buffer[48];
  if (a >= kCapMm - 1e-9) {
    std::snprintf(buffer, sizeof buffer, "more than %.1f mm %s", std::floor(kCapMm * 10) / 10,
                  margin_mm > 0 ? "to spare" : "too far");
  } else {
    std::snprintf(buffer, sizeof buffer, "%.1f mm %s", a, margin_mm > 0 ? "to spare" : "too far");
  }
  return buffer;
}

KnifeEdgeLook knife_edge_look(const prediction_t* p, int64_t anim_ms) {
  KnifeEdgeLook look;
  if (p == nullptr || p->status != prediction_t::STATUS_OK) return look;
  if (p->uncertainty > 0.0) look.margin_text = margin_text(p->margin_mm);
  if (p->verdict != prediction_t::VERDICT_KNIFE_EDGE) return look;
  look.knife_edge = true;
  for (const auto& b : p->blocks) {
    if (b.deciding) look.outlined.push_back(b.id);
  }
  const double phase = static_cast<double>(((anim_ms % kKnifeEdgePulseMs) + kKnifeEdgePulseMs) % kKnifeEdgePulseMs) /
                       static_cast<double>(kKnifeEdgePulseMs);
  const double level = 0.7 - 0.3 * std::cos(2.0 * M_PI * phase);  // 0.4 .. 1.0
  look.outline = Rgb{static_cast<uint8_t>(std::lround(255.0 * level)), 0};
  return look;
}

}  // namespace bricklayer::projection
