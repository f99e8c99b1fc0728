#include "tendril/core/schema.h"

#include <cmath>

namespace tendril::schema {

namespace {

constexpr double kPiDouble = 3.14159265358979323846;

std::string choiceList(const std::vector<std::string_view>& options) {
  std::string list;
  for (auto o : options) list += (list.empty() ? "\"" : ", \"") + std::string(o) + "\"";
  return list;
}

// What a float read from the file can be: the limits rounded to float as the values were.
bool withinFloat(double v, double min, double max) {
  return std::isfinite(v) && v >= double(float(min)) && v <= double(float(max));
}

std::string pointMessage() {
  return fmt::format("point must be finite and within {} m of the origin", JsonObject::kWorldExtent);
}

}  // namespace

double toDegrees(float radians) { return double(radians) * (180.0 / kPiDouble); }
float fromDegrees(double degrees) { return float(degrees * (kPiDouble / 180.0)); }

std::string_view kindName(Kind kind) {
  switch (kind) {
    case Kind::Number: return "number";
    case Kind::Angle: return "number (degrees)";
    case Kind::Integer: return "integer";
    case Kind::Seed: return "integer ≥ 0";
    case Kind::Boolean: return "boolean";
    case Kind::Choice: return "string";
    case Kind::Vec3: return "[x, y, z]";
    case Kind::Direction: return "[x, y, z]";
    case Kind::Points: return "array of [x, y, z]";
  }
  return "?";
}

std::string rangeText(double min, double max) {
  if (std::isinf(min) && std::isinf(max)) return "";
  if (std::isinf(max)) return fmt::format("at least {}", min);
  if (std::isinf(min)) return fmt::format("at most {}", max);
  return fmt::format("in [{}, {}]", min, max);
}

std::string formatNumber(double value) { return fmt::format("{}", value); }

namespace detail {

void read(JsonObject& o, const Limits& f, double* scalar, Vec3* vec, std::vector<Vec3>* points, uint64_t* seed) {
  switch (f.kind) {
    case Kind::Number:
    case Kind::Angle: {
      // The limits apply to the value as kept (a float; radians), as check() applies them: a
      // value written at a limit reads back although its decimal form lies a rounding beyond.
      *scalar = o.number(f.key, 0.0);
      const double kept = f.kind == Kind::Angle ? double(fromDegrees(*scalar)) : double(float(*scalar));
      const bool within = f.kind == Kind::Angle
                              ? kept >= double(fromDegrees(f.min)) && kept <= double(fromDegrees(f.max))
                              : withinFloat(kept, f.min, f.max);
      if (!within)
        throw o.error(f.key, fmt::format("must be {}, got {}", rangeText(f.min, f.max), o.json().at(f.key).dump()));
      return;
    }
    case Kind::Integer: *scalar = double(o.integer(f.key, 0, int64_t(f.min), int64_t(f.max))); return;
    case Kind::Seed: *seed = o.seed(f.key, 0); return;
    case Kind::Boolean: *scalar = o.boolean(f.key, false) ? 1.0 : 0.0; return;
    case Kind::Choice: {
      const std::string s = o.string(f.key, "");
      for (size_t i = 0; i < f.choices->size(); ++i)
        if ((*f.choices)[i] == s) {
          *scalar = double(i);
          return;
        }
      throw o.error(f.key, fmt::format("must be one of {}, got \"{}\"", choiceList(*f.choices), s));
    }
    case Kind::Vec3: *vec = o.vec3(f.key, Vec3::Zero(), f.min, f.max); return;
    case Kind::Direction:
      *vec = o.vec3(f.key, Vec3::Zero(), f.min, f.max);
      if (!(vec->norm() > 1e-6f)) throw o.error(f.key, "must be a non-zero direction");
      return;
    case Kind::Points: {
      const Json* pts = o.find(f.key);
      if (!pts || !pts->is_array() || pts->empty())
        throw o.error(f.key, "is required: a non-empty array of [x, y, z] points");
      points->clear();
      for (size_t i = 0; i < pts->size(); ++i) {
        const Json& p = (*pts)[i];
        const std::string at = o.pointerTo(f.key) + "/" + std::to_string(i);
        if (!p.is_array() || p.size() != 3 || !p[0].is_number() || !p[1].is_number() || !p[2].is_number())
          throw Error(o.source(), at, "expected [x, y, z], got " + describeJson(p));
        const Vec3 v(p[0].get<float>(), p[1].get<float>(), p[2].get<float>());
        if (!isFinite(v) || v.cwiseAbs().maxCoeff() > f.max) throw Error(o.source(), at, pointMessage());
        points->push_back(v);
      }
      return;
    }
  }
}

std::string check(const Limits& f, double scalar, const Vec3* vec, const std::vector<Vec3>* points,
                  std::string* below) {
  below->clear();
  switch (f.kind) {
    case Kind::Number:
      if (!withinFloat(scalar, f.min, f.max))
        return fmt::format("must be {}, got {}", rangeText(f.min, f.max), float(scalar));
      return "";
    case Kind::Angle:
      // In radians, against the limits as the reader converts them.
      if (!(std::isfinite(scalar) && scalar >= double(fromDegrees(f.min)) && scalar <= double(fromDegrees(f.max))))
        return fmt::format("must be {}, got {}", rangeText(f.min, f.max), float(toDegrees(float(scalar))));
      return "";
    case Kind::Integer:
    case Kind::Seed:
      if (!(scalar >= f.min && scalar <= f.max))
        return fmt::format("must be in [{}, {}], got {}", int64_t(f.min), int64_t(f.max), int64_t(scalar));
      return "";
    case Kind::Boolean: return "";
    case Kind::Choice:
      if (!(scalar >= 0.0 && scalar < double(f.choices->size())))
        return fmt::format("must be one of {}, got option {}", choiceList(*f.choices), int64_t(scalar));
      return "";
    case Kind::Vec3:
    case Kind::Direction:
      for (int i = 0; i < 3; ++i)
        if (!withinFloat((*vec)[i], f.min, f.max)) {
          *below = "/" + std::to_string(i);
          return fmt::format("must be {}, got {}", rangeText(f.min, f.max), (*vec)[i]);
        }
      if (f.kind == Kind::Direction && !(vec->norm() > 1e-6f)) return "must be a non-zero direction";
      return "";
    case Kind::Points:
      if (points->empty()) return "is required: a non-empty array of [x, y, z] points";
      for (size_t i = 0; i < points->size(); ++i) {
        const Vec3& p = (*points)[i];
        if (!isFinite(p) || p.cwiseAbs().maxCoeff() > f.max) {
          *below = "/" + std::to_string(i);
          return pointMessage();
        }
      }
      return "";
  }
  return "";
}

Json write(Kind kind, double scalar, const Vec3* vec, const std::vector<Vec3>* points,
           const std::vector<std::string_view>* choices) {
  auto vec3Json = [](const Vec3& v) { return Json::array({v.x(), v.y(), v.z()}); };
  switch (kind) {
    case Kind::Number:
    case Kind::Angle: return scalar;  // floats widen to double exactly; angles are degrees in double
    case Kind::Integer: return int64_t(scalar);
    case Kind::Seed: return uint64_t(scalar);
    case Kind::Boolean: return scalar != 0.0;
    case Kind::Choice: {
      const size_t i = size_t(scalar);
      return i < choices->size() ? Json(std::string((*choices)[i])) : Json(nullptr);
    }
    case Kind::Vec3:
    case Kind::Direction: return vec3Json(*vec);
    case Kind::Points: {
      Json list = Json::array();
      for (const Vec3& p : *points) list.push_back(vec3Json(p));
      return list;
    }
  }
  return nullptr;
}

}  // namespace detail

}  // namespace tendril::schema
