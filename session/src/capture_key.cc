#include "svbtdf/session/capture_key.h"

#include <array>
#include <charconv>

namespace svbtdf::session {
namespace {

// Field widths of the key grammar: view numbers are two digits, dot numbers four, so that keys
// sort in capture order in a file listing. Wider numbers are written in full.
constexpr int kViewDigits = 2;
constexpr int kDotDigits = 4;

std::string Padded(int value, int width) {
  std::string digits = std::to_string(value);
  if (static_cast<int>(digits.size()) < width) digits.insert(0, width - digits.size(), '0');
  return digits;
}

struct KindSpelling {
  CaptureKind kind;
  std::string_view name;
};
constexpr std::array<KindSpelling, 8> kKinds = {{
    {CaptureKind::kDark, "dark"},
    {CaptureKind::kBoardView, "board"},
    {CaptureKind::kSamplePlaneView, "sample_plane"},
    {CaptureKind::kMonitorPoseView, "monitor_pose"},
    {CaptureKind::kAllDots, "all_dots"},
    {CaptureKind::kFiducials, "fiducials"},
    {CaptureKind::kFlatWhite, "flat_white"},
    {CaptureKind::kDot, "dot"},
}};

// Splits "a/b/c" at its slashes.
std::vector<std::string_view> Split(std::string_view text) {
  std::vector<std::string_view> parts;
  size_t start = 0;
  while (true) {
    const size_t slash = text.find('/', start);
    parts.push_back(text.substr(start, slash - start));
    if (slash == std::string_view::npos) return parts;
    start = slash + 1;
  }
}

// `part` is `prefix` followed by a non-negative number of at least `width` digits, written
// without extra leading zeros (so that every key has exactly one spelling).
std::optional<int> Number(std::string_view part, char prefix, int width) {
  if (part.size() < 2 || part[0] != prefix) return std::nullopt;
  const std::string_view digits = part.substr(1);
  int value = 0;
  const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (error != std::errc() || end != digits.data() + digits.size() || value < 0) return std::nullopt;
  if (Padded(value, width) != digits) return std::nullopt;
  return value;
}

}  // namespace

std::string_view KindName(CaptureKind kind) {
  for (const KindSpelling& k : kKinds) {
    if (k.kind == kind) return k.name;
  }
  return "?";
}

std::string CaptureKey::Format() const {
  const std::string name(KindName(kind));
  switch (kind) {
    case CaptureKind::kDark:
      return name + "/e" + std::to_string(bracket) + "/r" + std::to_string(repeat);
    case CaptureKind::kBoardView:
    case CaptureKind::kSamplePlaneView:
    case CaptureKind::kMonitorPoseView:
      return name + "/v" + Padded(view, kViewDigits);
    case CaptureKind::kAllDots:
    case CaptureKind::kFiducials:
    case CaptureKind::kFlatWhite:
      return name + "/e" + std::to_string(bracket);
    case CaptureKind::kDot:
      return name + "/q" + Padded(dot, kDotDigits) + "/e" + std::to_string(bracket) + "/r" + std::to_string(repeat);
  }
  return name;
}

std::optional<CaptureKey> CaptureKey::Parse(std::string_view text) {
  const std::vector<std::string_view> parts = Split(text);
  std::optional<CaptureKind> kind;
  for (const KindSpelling& k : kKinds) {
    if (k.name == parts[0]) kind = k.kind;
  }
  if (!kind) return std::nullopt;
  CaptureKey key;
  key.kind = *kind;
  std::optional<int> a, b, c;
  switch (*kind) {
    case CaptureKind::kDark:
      if (parts.size() != 3 || !(a = Number(parts[1], 'e', 1)) || !(b = Number(parts[2], 'r', 1))) return std::nullopt;
      key.bracket = *a;
      key.repeat = *b;
      return key;
    case CaptureKind::kBoardView:
    case CaptureKind::kSamplePlaneView:
    case CaptureKind::kMonitorPoseView:
      if (parts.size() != 2 || !(a = Number(parts[1], 'v', kViewDigits))) return std::nullopt;
      key.view = *a;
      return key;
    case CaptureKind::kAllDots:
    case CaptureKind::kFiducials:
    case CaptureKind::kFlatWhite:
      if (parts.size() != 2 || !(a = Number(parts[1], 'e', 1))) return std::nullopt;
      key.bracket = *a;
      return key;
    case CaptureKind::kDot:
      if (parts.size() != 4 || !(a = Number(parts[1], 'q', kDotDigits)) || !(b = Number(parts[2], 'e', 1)) ||
          !(c = Number(parts[3], 'r', 1))) {
        return std::nullopt;
      }
      key.dot = *a;
      key.bracket = *b;
      key.repeat = *c;
      return key;
  }
  return std::nullopt;
}

std::vector<CaptureKey> CaptureOrder(const CaptureCounts& counts) {
  std::vector<CaptureKey> order;
  for (int e = 0; e < counts.brackets; ++e) {
    for (int n = 0; n < counts.dark_frames; ++n) order.push_back(CaptureKey::Dark(e, n));
  }
  for (int v = 0; v < counts.board_views; ++v) order.push_back(CaptureKey::BoardView(v));
  for (int v = 0; v < counts.sample_plane_views; ++v) order.push_back(CaptureKey::SamplePlaneView(v));
  if (counts.all_dots) order.push_back(CaptureKey::AllDots());
  if (counts.fiducials) order.push_back(CaptureKey::Fiducials());
  if (counts.flat_white) order.push_back(CaptureKey::FlatWhite());
  for (int q = 0; q < counts.dots; ++q) {
    for (int e = 0; e < counts.brackets; ++e) {
      for (int r = 0; r < counts.repeats; ++r) order.push_back(CaptureKey::Dot(q, e, r));
    }
  }
  return order;
}

}  // namespace svbtdf::session
