// Region settings: YAML / JSON (docs/formats.md, "Region settings").
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <initializer_list>
#include <sstream>
#include <utility>

#include "scanmesh/core/config_file.h"
#include "scanmesh/core/errors.h"
#include "scanmesh/core/texture_layout.h"
#include "scanmesh/meshing/aft/regions.h"

namespace scanmesh::aft {

namespace {

double number(const YAML::Node& n, const std::string& file, const std::string& key) {
  double v = 0;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    throw FileFormatError(file, key + " must be a number");
  }
  return v;
}

double positive(const YAML::Node& n, const std::string& file, const std::string& key) {
  const double v = number(n, file, key);
  if (!std::isfinite(v) || v <= 0) throw FileFormatError(file, key + " must be positive");
  return v;
}

std::string text(const YAML::Node& n, const std::string& file, const std::string& key) {
  if (!n.IsScalar()) throw FileFormatError(file, key + " must be a string");
  return n.as<std::string>();
}

std::string mesher_name(const YAML::Node& n, const std::string& file, const std::string& key) {
  const std::string m = text(n, file, key);
  if (m != "aft" && m != "delaunay")
    throw FileFormatError(file, key + " must be \"aft\" or \"delaunay\", not \"" + m + "\"");
  return m;
}

// A keyword setting: the value of the matching name, else an error listing the names
// ("key must be a, b or c").
template <typename Enum>
Enum keyword(const YAML::Node& n, const std::string& file, const std::string& key,
             std::initializer_list<std::pair<const char*, Enum>> choices) {
  const std::string m = text(n, file, key);
  const auto* c = choices.begin();
  std::string names;
  for (std::size_t k = 0; k < choices.size(); ++k) {
    if (m == c[k].first) return c[k].second;
    if (k > 0) names += k + 1 == choices.size() ? " or " : ", ";
    names += c[k].first;
  }
  throw FileFormatError(file, key + " must be " + names);
}

}  // namespace

RegionSettings parse_region_settings(std::string_view source, const std::string& file) {
  YAML::Node root;
  try {
    root = YAML::Load(std::string(source));
  } catch (const YAML::Exception& e) {
    throw FileFormatError(file, std::string("not valid YAML/JSON: ") + e.what());
  }
  RegionSettings s;
  if (root.IsNull()) return s;
  if (!root.IsMap()) throw FileFormatError(file, "expected a mapping at the top level");
  try {
    for (const auto& kv : root) {
      const std::string key = kv.first.as<std::string>();
      const YAML::Node& v = kv.second;
      if (key == "unit_mm") {
        s.default_unit_mm = positive(v, file, key);
      } else if (key == "mesher") {
        s.default_mesher = mesher_name(v, file, key);
      } else if (key == "strategy") {
        s.strategy = keyword<EdgeStrategy>(v, file, key,
                                           {{"random", EdgeStrategy::Random},
                                            {"shortest", EdgeStrategy::Shortest},
                                            {"longest", EdgeStrategy::Longest}});
      } else if (key == "segment_init") {
        s.segment_init = keyword<SegmentInit>(
            v, file, key,
            {{"equidistant", SegmentInit::Equidistant}, {"curvature", SegmentInit::Curvature}});
      } else if (key == "segment_spacing") {
        s.segment_spacing = keyword<SegmentSpacing>(
            v, file, key, {{"mean", SegmentSpacing::Mean}, {"finer", SegmentSpacing::Finer}});
      } else if (key == "curvature_weight_mm") {
        s.curvature_weight_mm = positive(v, file, key);
      } else if (key == "chordal_tolerance_mm") {
        s.chordal_tolerance_mm = positive(v, file, key);
      } else if (key == "min_unit_mm") {
        s.min_unit_mm = positive(v, file, key);
      } else if (key == "relax_iterations" || key == "smooth_iterations" ||
                 key == "repair_rounds") {
        const int n = v.as<int>();
        if (n < 0 || n > 1000) throw FileFormatError(file, key + " must be in 0..1000");
        (key == "relax_iterations"    ? s.relax_iterations
         : key == "smooth_iterations" ? s.smooth_iterations
                                      : s.repair_rounds) = n;
      } else if (key == "max_front_steps") {
        const long n = v.as<long>();
        if (n < 0) throw FileFormatError(file, "max_front_steps must be >= 0 (0: automatic)");
        s.max_front_steps = n;
      } else if (key == "repair_goal_deg") {
        // Above ~45 deg the goal is out of reach almost everywhere and the repair would only
        // burn time; below 10 it would leave the slivers it exists for.
        const double g = positive(v, file, key);
        if (g < 10 || g > 45) throw FileFormatError(file, "repair_goal_deg must be in 10..45");
        s.repair_goal_deg = g;
      } else if (key == "deviation_goal_mm") {
        const double d = number(v, file, key);
        if (!std::isfinite(d) || d < 0)
          throw FileFormatError(file, key + " must be a finite number >= 0 (0: off)");
        s.deviation_goal_mm = d;
      } else if (key == "parallel_postprocessing" || key == "valence_flips") {
        if (!v.IsScalar() || (v.Scalar() != "true" && v.Scalar() != "false"))
          throw FileFormatError(file, key + " must be true or false");
        (key == "valence_flips" ? s.valence_flips : s.parallel_postprocessing) =
            v.Scalar() == "true";
      } else if (key == "data_border") {
        s.data_border = keyword<DataBorderMode>(v, file, key,
                                                {{"auto", DataBorderMode::Auto},
                                                 {"on", DataBorderMode::On},
                                                 {"off", DataBorderMode::Off}});
      } else if (key == "seed") {
        s.seed = v.as<std::uint64_t>();
      } else if (key == "regions") {
        if (!v.IsSequence()) throw FileFormatError(file, "regions must be a list");
        int index = 0;
        for (const auto& r : v) {
          const std::string where = "regions[" + std::to_string(index++) + "]";
          if (!r.IsMap()) throw FileFormatError(file, where + " must be a mapping");
          RegionRule rule;
          rule.name = where;
          for (const auto& rk : r) {
            const std::string k = rk.first.as<std::string>();
            const YAML::Node& rv = rk.second;
            if (k == "name") {
              rule.name = text(rv, file, where + ".name");
            } else if (k == "point") {
              if (!rv.IsSequence() || rv.size() != 2)
                throw FileFormatError(file, where + ".point must be [x, y] in texture pixels");
              const Eigen::Vector2d p(rv[0].as<double>(), rv[1].as<double>());
              if (!p.allFinite()) throw FileFormatError(file, where + ".point is not finite");
              rule.point_px = p;
            } else if (k == "unit_mm") {
              rule.unit_mm = positive(rv, file, where + ".unit_mm");
            } else if (k == "mesher") {
              rule.mesher = mesher_name(rv, file, where + ".mesher");
            } else {
              throw FileFormatError(file, where + ": unknown key \"" + k + "\"");
            }
          }
          if (!rule.point_px)
            throw FileFormatError(file, where + " needs a point inside the region");
          s.regions.push_back(rule);
        }
      } else {
        throw FileFormatError(file, "unknown key \"" + key + "\"");
      }
    }
  } catch (const YAML::Exception& e) {
    throw FileFormatError(file, std::string("wrong value type: ") + e.what());
  }
  if (s.min_unit_mm > s.default_unit_mm)
    throw FileFormatError(file, "min_unit_mm is larger than unit_mm");
  // The same floor for every region's own unit: below it the front would take millions of
  // steps (a 0.05 mm unit on a head: minutes), which min_unit_mm exists to prevent.
  for (const RegionRule& rule : s.regions)
    if (rule.unit_mm && *rule.unit_mm < s.min_unit_mm)
      throw FileFormatError(file, rule.name + ".unit_mm " + format_number(*rule.unit_mm) +
                                      " mm is below min_unit_mm " + format_number(s.min_unit_mm) +
                                      " mm");
  return s;
}

void to_grid_rows(RegionSettings& settings, int n_h) {
  if (n_h < 1) throw InvalidInputError("to_grid_rows: the texture needs at least one row");
  for (RegionRule& rule : settings.regions)
    if (rule.point_px) rule.point_px = texture_to_grid_pixel(*rule.point_px, n_h);
  settings.texture_rows = n_h;
}

RegionSettings read_region_settings(const std::filesystem::path& path, int n_h, FileRows rows) {
  RegionSettings settings = parse_region_settings(read_config_text(path), path.string());
  if (rows == FileRows::FromTop) to_grid_rows(settings, n_h);
  return settings;
}

void apply_region_settings(RegionGraph& g, const RegionSettings& s, const ScanSurface& surface) {
  for (Region& r : g.regions) {
    r.unit_mm = s.default_unit_mm;
    r.mesher = s.default_mesher;
  }
  for (const RegionRule& rule : s.regions) {
    const auto r = g.region_at(pixel_to_param(surface, *rule.point_px));
    if (!r) {
      std::ostringstream os;
      const Eigen::Vector2d p = s.texture_rows > 0
                                    ? texture_to_grid_pixel(*rule.point_px, s.texture_rows)
                                    : *rule.point_px;
      os << "region setting '" << rule.name << "': point (" << p.x() << ", " << p.y()
         << ") lies in no region";
      throw InvalidInputError(os.str());
    }
    Region& reg = g.regions[*r];
    reg.name = rule.name;
    if (rule.unit_mm) reg.unit_mm = *rule.unit_mm;
    if (rule.mesher) reg.mesher = *rule.mesher;
  }
}

RegionSettings RegionSettings::with_units_scaled(double factor) const {
  RegionSettings scaled = *this;
  scaled.default_unit_mm *= factor;
  for (RegionRule& rule : scaled.regions)
    if (rule.unit_mm) *rule.unit_mm *= factor;
  return scaled;
}

}  // namespace scanmesh::aft
