// Animation-line input: SVG and JSON readers, pixel <-> (phi, h), surface checks.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "scanmesh/core/atomic_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/texture_layout.h"
#include "scanmesh/meshing/aft/animation_lines.h"

namespace scanmesh::aft {

using Eigen::Vector2d;

const char* to_string(LineKind kind) {
  return kind == LineKind::Opening      ? "opening"
         : kind == LineKind::Seam       ? "seam"
         : kind == LineKind::DataBorder ? "data-border"
                                        : "line";
}

namespace {

constexpr int kCurvePieces = 24;  // flattening of one Bezier piece / spline span
constexpr std::size_t kMaxPoints = 200000;

[[noreturn]] void fail(const std::string& file, int line, const std::string& what) {
  throw FileFormatError(file, "line " + std::to_string(line) + ": " + what);
}

int line_of(std::string_view text, std::size_t pos) {
  return 1 + static_cast<int>(
                 std::count(text.begin(), text.begin() + std::min(pos, text.size()), '\n'));
}

bool has_token(const std::string& s, const char* token) {
  std::string lower = s;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower.find(token) != std::string::npos;
}

// ---- SVG -----------------------------------------------------------------------------------

struct Element {
  std::string name;
  std::map<std::string, std::string> attrs;
  int line = 1;
};

class PathParser {
 public:
  PathParser(const std::string& d, const std::string& file, int line)
      : d_(d), file_(file), line_(line) {}

  // Subpaths as (points, closed).
  std::vector<std::pair<std::vector<Vector2d>, bool>> parse() {
    std::vector<std::pair<std::vector<Vector2d>, bool>> out;
    std::vector<Vector2d> cur;
    bool closed = false;
    Vector2d pos(0, 0), start(0, 0), last_ctrl(0, 0);
    char prev_cmd = 0;
    char cmd = 0;
    auto flush = [&] {
      if (cur.size() >= 1) out.emplace_back(cur, closed);
      cur.clear();
      closed = false;
    };
    auto add = [&](const Vector2d& p) {
      if (cur.size() >= kMaxPoints) fail(file_, line_, "path has too many points");
      cur.push_back(p);
    };
    // The first control point of a Bezier command at pos: read for the explicit form (C, Q);
    // for the smooth form (S, T) the previous control point reflected through pos if the
    // previous command drew the same kind of curve, else pos itself (the SVG path rules).
    auto first_control_point = [&](char explicit_cmd, char smooth_cmd,
                                   const Vector2d& base) -> Vector2d {
      if (std::toupper(static_cast<unsigned char>(cmd)) == explicit_cmd) return base + point();
      const char p = static_cast<char>(std::toupper(static_cast<unsigned char>(prev_cmd)));
      return (p == explicit_cmd || p == smooth_cmd) ? Vector2d(2 * pos - last_ctrl) : pos;
    };
    while (true) {
      skip_separators();
      if (i_ >= d_.size()) break;
      const char c = d_[i_];
      if (std::isalpha(static_cast<unsigned char>(c))) {
        cmd = c;
        ++i_;
      } else if (cmd == 0) {
        fail(file_, line_,
             "path data must start with a command, found '" + std::string(1, c) + "'");
      } else if (cmd == 'M') {
        cmd = 'L';  // implicit lineto after moveto
      } else if (cmd == 'm') {
        cmd = 'l';
      } else if (cmd == 'Z' || cmd == 'z') {
        fail(file_, line_, "numbers after Z in path data");
      }
      const bool rel = std::islower(static_cast<unsigned char>(cmd)) != 0;
      const Vector2d base = rel ? pos : Vector2d(0, 0);
      switch (std::toupper(static_cast<unsigned char>(cmd))) {
        case 'M': {
          flush();
          pos = base + point();
          start = pos;
          add(pos);
          break;
        }
        case 'L':
          need_start(cur, pos);
          pos = base + point();
          add(pos);
          break;
        case 'H':
          need_start(cur, pos);
          pos.x() = (rel ? pos.x() : 0) + number();
          add(pos);
          break;
        case 'V':
          need_start(cur, pos);
          pos.y() = (rel ? pos.y() : 0) + number();
          add(pos);
          break;
        case 'C':
        case 'S': {
          need_start(cur, pos);
          const Vector2d c1 = first_control_point('C', 'S', base);
          const Vector2d c2 = base + point();
          const Vector2d p3 = base + point();
          for (int k = 1; k <= kCurvePieces; ++k) {
            const double t = static_cast<double>(k) / kCurvePieces, s = 1 - t;
            add(s * s * s * pos + 3 * s * s * t * c1 + 3 * s * t * t * c2 + t * t * t * p3);
          }
          last_ctrl = c2;
          pos = p3;
          break;
        }
        case 'Q':
        case 'T': {
          need_start(cur, pos);
          const Vector2d c1 = first_control_point('Q', 'T', base);
          const Vector2d p2 = base + point();
          for (int k = 1; k <= kCurvePieces; ++k) {
            const double t = static_cast<double>(k) / kCurvePieces, s = 1 - t;
            add(s * s * pos + 2 * s * t * c1 + t * t * p2);
          }
          last_ctrl = c1;
          pos = p2;
          break;
        }
        case 'Z':
          closed = true;
          pos = start;
          flush();
          break;
        case 'A':
          fail(file_, line_, "elliptical arcs (A) are not supported; use Bezier curves");
        default:
          fail(file_, line_, "unknown path command '" + std::string(1, cmd) + "'");
      }
      prev_cmd = cmd;
    }
    flush();
    return out;
  }

 private:
  void need_start(const std::vector<Vector2d>& cur, const Vector2d&) {
    if (cur.empty()) fail(file_, line_, "path draws before its first M");
  }
  void skip_separators() {
    while (i_ < d_.size() && (std::isspace(static_cast<unsigned char>(d_[i_])) || d_[i_] == ','))
      ++i_;
  }
  double number() {
    skip_separators();
    const char* begin = d_.c_str() + i_;
    char* end = nullptr;
    const double v = std::strtod(begin, &end);
    if (end == begin)
      fail(file_, line_, "expected a number in path data at offset " + std::to_string(i_));
    if (!std::isfinite(v)) fail(file_, line_, "non-finite number in path data");
    i_ += static_cast<std::size_t>(end - begin);
    return v;
  }
  Vector2d point() {
    const double x = number();
    const double y = number();
    return {x, y};
  }

  const std::string& d_;
  const std::string& file_;
  int line_;
  std::size_t i_ = 0;
};

std::vector<Vector2d> parse_points(const std::string& s, const std::string& file, int line) {
  std::vector<double> v;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (std::isspace(static_cast<unsigned char>(s[i])) || s[i] == ',')) ++i;
    if (i >= s.size()) break;
    const char* begin = s.c_str() + i;
    char* end = nullptr;
    const double x = std::strtod(begin, &end);
    if (end == begin || !std::isfinite(x)) fail(file, line, "malformed number in points=\"...\"");
    i += static_cast<std::size_t>(end - begin);
    v.push_back(x);
    if (v.size() > 2 * kMaxPoints) fail(file, line, "too many points");
  }
  if (v.size() % 2) fail(file, line, "odd number of coordinates in points=\"...\"");
  std::vector<Vector2d> p;
  for (std::size_t k = 0; k + 1 < v.size(); k += 2) p.emplace_back(v[k], v[k + 1]);
  return p;
}

std::vector<Element> scan_elements(std::string_view text, const std::string& file) {
  std::vector<Element> out;
  std::size_t i = 0;
  while (true) {
    i = text.find('<', i);
    if (i == std::string_view::npos) break;
    if (text.substr(i, 4) == "<!--") {
      const std::size_t e = text.find("-->", i + 4);
      if (e == std::string_view::npos) fail(file, line_of(text, i), "unterminated comment");
      i = e + 3;
      continue;
    }
    if (i + 1 < text.size() && (text[i + 1] == '?' || text[i + 1] == '!' || text[i + 1] == '/')) {
      const std::size_t e = text.find('>', i + 1);
      if (e == std::string_view::npos) fail(file, line_of(text, i), "unterminated tag");
      i = e + 1;
      continue;
    }
    Element el;
    el.line = line_of(text, i);
    std::size_t k = i + 1;
    while (k < text.size() && (std::isalnum(static_cast<unsigned char>(text[k])) ||
                               text[k] == ':' || text[k] == '-' || text[k] == '_'))
      ++k;
    el.name = std::string(text.substr(i + 1, k - i - 1));
    // attributes
    while (true) {
      while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
      if (k >= text.size()) fail(file, el.line, "unterminated <" + el.name + "> tag");
      if (text[k] == '>' || text[k] == '/') {
        const std::size_t e = text.find('>', k);
        if (e == std::string_view::npos) fail(file, el.line, "unterminated <" + el.name + "> tag");
        k = e + 1;
        break;
      }
      std::size_t a = k;
      while (k < text.size() && text[k] != '=' &&
             !std::isspace(static_cast<unsigned char>(text[k])) && text[k] != '>')
        ++k;
      const std::string key(text.substr(a, k - a));
      while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
      if (k >= text.size() || text[k] != '=') {
        if (key.empty()) fail(file, el.line, "malformed attribute in <" + el.name + ">");
        el.attrs[key] = "";
        continue;
      }
      ++k;
      while (k < text.size() && std::isspace(static_cast<unsigned char>(text[k]))) ++k;
      if (k >= text.size() || (text[k] != '"' && text[k] != '\''))
        fail(file, el.line, "attribute " + key + " of <" + el.name + "> is not quoted");
      const char q = text[k];
      const std::size_t e = text.find(q, k + 1);
      if (e == std::string_view::npos) fail(file, el.line, "unterminated attribute " + key);
      el.attrs[key] = std::string(text.substr(k + 1, e - k - 1));
      k = e + 1;
    }
    out.push_back(std::move(el));
    i = k;
  }
  return out;
}

void set_kind(AnimationLine& line, const Element& el, const std::string& file) {
  std::string tags;
  if (auto it = el.attrs.find("id"); it != el.attrs.end()) tags += it->second + " ";
  if (auto it = el.attrs.find("class"); it != el.attrs.end()) tags += it->second;
  if (has_token(tags, "opening")) line.kind = LineKind::Opening;
  if (has_token(tags, "seam")) line.kind = LineKind::Seam;
  for (const char* key : {"data-spacing-mm", "data-node-spacing", "spacing"}) {
    auto it = el.attrs.find(key);
    if (it == el.attrs.end()) continue;
    char* end = nullptr;
    const double v = std::strtod(it->second.c_str(), &end);
    if (end == it->second.c_str() || !std::isfinite(v) || v <= 0)
      fail(file, el.line, std::string(key) + " must be a positive number of millimetres");
    line.node_spacing_mm = v;
  }
}

// Through the points p (x unwrapped); a closed curve continues periodically, each turn shifted
// by `turn` in x (0, or the width for a line that goes round the axis).
std::vector<Vector2d> catmull_rom(const std::vector<Vector2d>& p, bool closed, double turn) {
  const int n = static_cast<int>(p.size());
  if (n < 3) return p;
  auto at = [&](int k) -> Vector2d {
    if (closed) {
      const int wraps = static_cast<int>(std::floor(static_cast<double>(k) / n));
      return p[k - wraps * n] + Vector2d(wraps * turn, 0);
    }
    if (k < 0) return 2 * p[0] - p[1];
    if (k >= n) return 2 * p[n - 1] - p[n - 2];
    return p[k];
  };
  std::vector<Vector2d> out;
  const int spans = closed ? n : n - 1;
  out.push_back(p[0]);
  for (int s = 0; s < spans; ++s) {
    const Vector2d P0 = at(s - 1), P1 = at(s), P2 = at(s + 1), P3 = at(s + 2);
    auto knot = [](const Vector2d& a, const Vector2d& b) {
      return std::max(std::sqrt((b - a).norm()), 1e-6);
    };
    const double t0 = 0, t1 = t0 + knot(P0, P1), t2 = t1 + knot(P1, P2), t3 = t2 + knot(P2, P3);
    for (int k = 1; k <= kCurvePieces; ++k) {
      const double t = t1 + (t2 - t1) * k / kCurvePieces;
      const Vector2d A1 = (t1 - t) / (t1 - t0) * P0 + (t - t0) / (t1 - t0) * P1;
      const Vector2d A2 = (t2 - t) / (t2 - t1) * P1 + (t - t1) / (t2 - t1) * P2;
      const Vector2d A3 = (t3 - t) / (t3 - t2) * P2 + (t - t2) / (t3 - t2) * P3;
      const Vector2d B1 = (t2 - t) / (t2 - t0) * A1 + (t - t0) / (t2 - t0) * A2;
      const Vector2d B2 = (t3 - t) / (t3 - t1) * A2 + (t - t1) / (t3 - t1) * A3;
      out.push_back((t2 - t) / (t2 - t1) * B1 + (t - t1) / (t2 - t1) * B2);
    }
  }
  if (closed) out.pop_back();
  return out;
}

// Removes repeated points; a closed line loses a repeated first point at its end.
void tidy(AnimationLine& line, const std::string& file, int src_line) {
  std::vector<Vector2d> p;
  for (const Vector2d& q : line.pixels)
    if (p.empty() || (q - p.back()).norm() > 1e-9) p.push_back(q);
  if (line.closed && p.size() > 1 && (p.front() - p.back()).norm() <= 1e-9) p.pop_back();
  if (!line.closed && p.size() > 2 && (p.front() - p.back()).norm() <= 1e-9) {
    p.pop_back();
    line.closed = true;
  }
  line.pixels = std::move(p);
  if (line.pixels.size() < (line.closed ? 3u : 2u))
    fail(file, src_line,
         "line '" + line.id + "' is too short (fewer than " + (line.closed ? "3" : "2") +
             " distinct points)");
}

}  // namespace

LineSet parse_lines_svg(std::string_view text, const std::string& file) {
  LineSet set;
  set.file = file;
  const std::vector<Element> elements = scan_elements(text, file);
  bool saw_svg = false;
  for (const Element& el : elements) {
    if (el.name == "svg") saw_svg = true;
    if (el.attrs.count("transform"))
      fail(file, el.line, "transform attributes are not supported: draw in texture pixels");
    std::vector<std::pair<std::vector<Vector2d>, bool>> parts;
    if (el.name == "path") {
      auto it = el.attrs.find("d");
      if (it == el.attrs.end()) fail(file, el.line, "<path> without d");
      parts = PathParser(it->second, file, el.line).parse();
    } else if (el.name == "polyline" || el.name == "polygon") {
      auto it = el.attrs.find("points");
      if (it == el.attrs.end()) fail(file, el.line, "<" + el.name + "> without points");
      parts.emplace_back(parse_points(it->second, file, el.line), el.name == "polygon");
    } else if (el.name == "line") {
      std::array<double, 4> v{};
      const char* keys[] = {"x1", "y1", "x2", "y2"};
      for (int k = 0; k < 4; ++k) {
        auto it = el.attrs.find(keys[k]);
        if (it == el.attrs.end()) fail(file, el.line, std::string("<line> without ") + keys[k]);
        char* end = nullptr;
        v[k] = std::strtod(it->second.c_str(), &end);
        if (end == it->second.c_str() || !std::isfinite(v[k]))
          fail(file, el.line, std::string("<line> ") + keys[k] + " is not a number");
      }
      parts.push_back({{Vector2d(v[0], v[1]), Vector2d(v[2], v[3])}, false});
    } else {
      continue;
    }
    for (std::size_t k = 0; k < parts.size(); ++k) {
      AnimationLine line;
      auto id = el.attrs.find("id");
      line.id = id != el.attrs.end() && !id->second.empty()
                    ? id->second
                    : "line-" + std::to_string(set.lines.size() + 1);
      if (parts.size() > 1) line.id += "#" + std::to_string(k + 1);
      set_kind(line, el, file);
      line.pixels = std::move(parts[k].first);
      line.closed = parts[k].second;
      line.source = file + ":" + std::to_string(el.line);
      tidy(line, file, el.line);
      // class "smooth": the spline through the drawn points, as JSON's "smooth": true (a
      // polyline is otherwise taken as drawn, straight pieces and corners). It is traced by
      // line_curve, after the points are joined across the phi seam.
      if (const auto cls = el.attrs.find("class");
          cls != el.attrs.end() && has_token(cls->second, "smooth")) {
        if (line.pixels.size() * kCurvePieces > kMaxPoints)
          fail(file, el.line, "line '" + line.id + "' has too many points to smooth");
        line.smooth = true;
      }
      set.lines.push_back(std::move(line));
    }
  }
  if (!saw_svg) throw FileFormatError(file, "not an SVG file (no <svg> element)");
  if (set.lines.empty()) throw FileFormatError(file, "no lines (path, polyline, polygon, line)");
  return set;
}

LineSet parse_lines_json(std::string_view text, const std::string& file) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw FileFormatError(file, std::string("not valid JSON: ") + e.what());
  }
  LineSet set;
  set.file = file;
  if (!j.is_object() || !j.contains("lines") || !j["lines"].is_array())
    throw FileFormatError(file, "expected an object with a \"lines\" array");
  int index = 0;
  for (const auto& jl : j["lines"]) {
    ++index;
    const std::string where = "lines[" + std::to_string(index - 1) + "]";
    if (!jl.is_object()) throw FileFormatError(file, where + " is not an object");
    AnimationLine line;
    line.id = "line-" + std::to_string(index);
    for (const auto& [key, v] : jl.items()) {
      if (key == "id") {
        if (!v.is_string()) throw FileFormatError(file, where + ".id must be a string");
        line.id = v.get<std::string>();
      } else if (key == "kind") {
        const std::string k = v.is_string() ? v.get<std::string>() : "";
        if (k == "opening")
          line.kind = LineKind::Opening;
        else if (k == "seam")
          line.kind = LineKind::Seam;
        else if (k == "line")
          line.kind = LineKind::Normal;
        else
          throw FileFormatError(file, where + ".kind must be \"line\", \"opening\" or \"seam\"");
      } else if (key == "spacing_mm") {
        if (!v.is_number() || !(v.get<double>() > 0) || !std::isfinite(v.get<double>()))
          throw FileFormatError(file, where + ".spacing_mm must be a positive number");
        line.node_spacing_mm = v.get<double>();
      } else if (key == "closed") {
        if (!v.is_boolean()) throw FileFormatError(file, where + ".closed must be true or false");
        line.closed = v.get<bool>();
      } else if (key == "smooth") {
        if (!v.is_boolean()) throw FileFormatError(file, where + ".smooth must be true or false");
        line.smooth = v.get<bool>();
      } else if (key == "points") {
        if (!v.is_array()) throw FileFormatError(file, where + ".points must be an array");
        if (v.size() > kMaxPoints) throw FileFormatError(file, where + " has too many points");
        for (const auto& p : v) {
          if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number())
            throw FileFormatError(file, where + ".points: each point is [x, y]");
          const Vector2d q(p[0].get<double>(), p[1].get<double>());
          if (!q.allFinite()) throw FileFormatError(file, where + ".points: non-finite value");
          line.pixels.push_back(q);
        }
      } else {
        throw FileFormatError(file, where + ": unknown key \"" + key + "\"");
      }
    }
    if (line.smooth && line.pixels.size() * kCurvePieces > kMaxPoints)
      throw FileFormatError(file, where + " has too many points to smooth");
    line.source = file + ":" + where;
    std::vector<Vector2d> p;
    for (const Vector2d& q : line.pixels)
      if (p.empty() || (q - p.back()).norm() > 1e-9) p.push_back(q);
    if (line.closed && p.size() > 1 && (p.front() - p.back()).norm() <= 1e-9) p.pop_back();
    line.pixels = p;
    if (line.pixels.size() < (line.closed ? 3u : 2u))
      throw FileFormatError(file, where + " ('" + line.id + "') is too short");
    set.lines.push_back(std::move(line));
  }
  if (set.lines.empty()) throw FileFormatError(file, "no lines");
  return set;
}

namespace {

LineSet read_lines_as_written(const std::filesystem::path& path) {
  const std::vector<std::uint8_t> bytes = read_file_bytes(path, kMaxTextInputBytes);
  const std::string text(bytes.begin(), bytes.end());
  std::string ext = path.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".json") return parse_lines_json(text, path.string());
  if (ext == ".svg") return parse_lines_svg(text, path.string());
  throw FileFormatError(path, "animation lines must be .svg or .json");
}

}  // namespace

FileRows parse_file_rows(const std::string& text) {
  if (text == "top") return FileRows::FromTop;
  if (text == "bottom") return FileRows::FromBottom;
  throw InvalidInputError(
      "line rows must be 'top' (rows counted down from the top of the "
      "upright texture) or 'bottom' (older files: h rows up), got '" +
      text + "'");
}

void to_grid_rows(LineSet& lines, int n_h) {
  if (n_h < 1) throw InvalidInputError("to_grid_rows: the texture needs at least one row");
  for (AnimationLine& line : lines.lines)
    for (Vector2d& p : line.pixels) p = texture_to_grid_pixel(p, n_h);
  lines.texture_rows = n_h;
}

Vector2d file_pixel(const LineSet& lines, const Vector2d& grid_pixel) {
  return lines.texture_rows > 0 ? texture_to_grid_pixel(grid_pixel, lines.texture_rows)
                                : grid_pixel;
}

LineSet read_lines(const std::filesystem::path& path, int n_h, FileRows rows) {
  LineSet set = read_lines_as_written(path);
  if (rows == FileRows::FromTop) to_grid_rows(set, n_h);
  return set;
}

Vector2d pixel_to_param(const ScanSurface& s, const Vector2d& px) {
  return {s.phi0() + (px.x() - 0.5) * s.dphi(), s.h0() + (px.y() - 0.5) * s.dh()};
}

Vector2d param_to_pixel(const ScanSurface& s, const Vector2d& p) {
  return {(p.x() - s.phi0()) / s.dphi() + 0.5, (p.y() - s.h0()) / s.dh() + 0.5};
}

std::vector<Vector2d> line_curve(const AnimationLine& line, double width) {
  std::vector<Vector2d> joined;
  joined.reserve(line.pixels.size());
  for (const Vector2d& p : line.pixels) {
    Vector2d q = p;
    if (!joined.empty()) q.x() += width * std::round((joined.back().x() - q.x()) / width);
    joined.push_back(q);
  }
  if (!line.smooth) return joined;
  // A closed line's last point joins its first one turn on if the line goes round the axis.
  const double turn = line.closed && !joined.empty()
                          ? width * std::round((joined.back().x() - joined.front().x()) / width)
                          : 0.0;
  return catmull_rom(joined, line.closed, turn);
}

void validate_lines(const LineSet& set, const ScanSurface& surface) {
  const double W = surface.n_phi();
  for (const AnimationLine& line : set.lines) {
    const std::string who = "line '" + line.id + "' (" + line.source + ")";
    auto leaves_at = [&](const Vector2d& p) {
      std::ostringstream os;
      os.precision(1);
      const Vector2d f = file_pixel(set, p);
      os << std::fixed << who << " leaves the scanned area at pixel (" << f.x() << ", " << f.y()
         << ")";
      throw FileFormatError(set.file, os.str());
    };
    double length_px = 0;
    // Lines may run past the texture's right edge (across the phi seam), but not by turns: a
    // far-off x would wrap round many times and make the sampling below loop for ever.
    const double x_limit = 4.0 * surface.n_phi();
    for (const Vector2d& p : line.pixels)
      if (!(std::abs(p.x()) <= x_limit)) {
        std::ostringstream os;
        os << who << " has a point at x = " << p.x() << ", more than " << x_limit
           << " pixels from the texture (lines may cross its phi seam, not wind round)";
        throw FileFormatError(set.file, os.str());
      } else if (!(p.y() >= 0.5 && p.y() <= surface.n_h() - 0.5)) {
        leaves_at(p);
      }
    // The curve as analyze_regions uses it (joined across the seam, smoothed); each piece is
    // followed the short way round, the closing piece of a line that goes round included.
    const std::vector<Vector2d> curve = line_curve(line, W);
    const std::size_t n = curve.size();
    const std::size_t pieces = line.closed ? n : n - 1;
    for (std::size_t k = 0; k < pieces; ++k) {
      const Vector2d a = curve[k];
      Vector2d b = curve[(k + 1) % n];
      b.x() += W * std::round((a.x() - b.x()) / W);
      length_px += (b - a).norm();
      const int steps = std::max(1, static_cast<int>(std::ceil((b - a).norm() * 4)));
      for (int s = 0; s <= steps; ++s) {
        const Vector2d p = a + (b - a) * (static_cast<double>(s) / steps);
        const Vector2d q = pixel_to_param(surface, p);
        if (p.y() < 0.5 || p.y() > surface.n_h() - 0.5 || !surface.defined(q.x(), q.y()))
          leaves_at(p);
      }
    }
    if (length_px < 2.0) throw FileFormatError(set.file, who + " is too short (under 2 pixels)");
  }
}

}  // namespace scanmesh::aft
