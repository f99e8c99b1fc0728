// One description per settings type: every field of a settings struct described once — its
// JSON key, kind, range, unit, default, label and a line of documentation — and the reading,
// writing and checking that follow from it.
//
// The same description reads a scene file's object, an edit script's, writes an edit back
// (bit for bit: angles are degrees in files and radians in memory, converted in double),
// checks values that arrive without JSON (saved session states, the studio's widgets) against
// the very limits the readers apply, gives the studio its widgets' labels and ranges and the
// docs their tables. Reading is strict as JsonObject is: the caller finishes the object (an
// edit's object holds keys of its own besides the settings').
#pragma once

#include "tendril/core/json_reader.h"
#include "tendril/core/math.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace tendril::schema {

// Degrees in files, radians in memory; in double, so that a float survives the round trip.
double toDegrees(float radians);
float fromDegrees(double degrees);

enum class Kind {
  Number,     // a float member, in [min, max]
  Angle,      // a float member in radians, given in degrees in [min, max]
  Integer,    // an int member, in [min, max]
  Seed,       // a uint64_t member, 0 to 2^53
  Boolean,    // a bool member
  Choice,     // one of `choices`, kept as an index (an enum) through get/set
  Vec3,       // [x, y, z], each in [min, max]
  Direction,  // [x, y, z], non-zero, kept as written (users normalise it)
  Points,     // a non-empty array of [x, y, z] within the world's extent
};

// The kind's name in documentation, e.g. "number".
std::string_view kindName(Kind kind);
// How `min`/`max` read in messages: "in [0, 45]", "at least 0", "" for no limits.
std::string rangeText(double min, double max);
// A number as the docs and messages write it (shortest form, no trailing ".0").
std::string formatNumber(double value);

template <class T>
struct Field {
  std::string_view key;
  Kind kind = Kind::Number;
  std::string_view label;  // for widgets, e.g. "speed"
  std::string_view unit;   // "m", "m/s", "deg", "s", "" (none)
  std::string_view doc;    // one line for people (also what "is required (...)" says)
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  double fallback = 0.0;            // the default, in file units (degrees for angles)
  Vec3 fallbackVec = Vec3::Zero();  // Vec3, Direction
  bool required = false;
  std::vector<std::string_view> choices;  // Choice
  int (*getChoice)(const T&) = nullptr;
  void (*setChoice)(T&, int) = nullptr;
  std::variant<std::monostate, float T::*, int T::*, uint64_t T::*, bool T::*, Vec3 T::*, std::vector<Vec3> T::*>
      member;

  // Where a widget's slider runs, when narrower than the valid range (a species' growth speed
  // may be 1e6; its slider stops at 100). Values beyond it are still valid when typed or read.
  double sliderMin = std::numeric_limits<double>::quiet_NaN();
  double sliderMax = std::numeric_limits<double>::quiet_NaN();

  Field& require() {
    required = true;
    return *this;
  }
  Field& slider(double lo, double hi) {
    sliderMin = lo, sliderMax = hi;
    return *this;
  }
  double sliderLow() const { return sliderMin == sliderMin ? sliderMin : min; }
  double sliderHigh() const { return sliderMax == sliderMax ? sliderMax : max; }
  // The label with its unit, as a widget shows it: "speed (m/s)".
  std::string labelWithUnit() const {
    return unit.empty() ? std::string(label) : std::string(label) + " (" + std::string(unit) + ")";
  }
};

template <class T>
struct Schema {
  std::string_view name;  // e.g. "light"
  std::vector<Field<T>> fields;

  const Field<T>* find(std::string_view key) const {
    for (const Field<T>& f : fields)
      if (f.key == key) return &f;
    return nullptr;
  }
  const Field<T>& at(std::string_view key) const {
    const Field<T>* f = find(key);
    if (!f) throw Error("", "", fmt::format("the {} settings have no key \"{}\"", name, key));
    return *f;
  }
};

// --- describing fields ---

template <class T>
Field<T> makeField(std::string_view key, Kind kind, std::string_view label, std::string_view unit,
                   std::string_view doc, double min, double max, double fallback) {
  Field<T> f;
  f.key = key, f.kind = kind, f.label = label, f.unit = unit, f.doc = doc;
  f.min = min, f.max = max, f.fallback = fallback;
  return f;
}

template <class T>
Field<T> number(std::string_view key, float T::*m, double fallback, double min, double max, std::string_view unit,
                std::string_view label, std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Number, label, unit, doc, min, max, fallback);
  f.member = m;
  return f;
}

template <class T>
Field<T> angle(std::string_view key, float T::*m, double fallbackDegrees, double minDegrees, double maxDegrees,
               std::string_view label, std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Angle, label, "deg", doc, minDegrees, maxDegrees, fallbackDegrees);
  f.member = m;
  return f;
}

template <class T>
Field<T> integer(std::string_view key, int T::*m, int fallback, int min, int max, std::string_view label,
                 std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Integer, label, "", doc, double(min), double(max), double(fallback));
  f.member = m;
  return f;
}

template <class T>
Field<T> seed(std::string_view key, uint64_t T::*m, uint64_t fallback, std::string_view label, std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Seed, label, "", doc, 0.0, double(int64_t(1) << 53), double(fallback));
  f.member = m;
  return f;
}

template <class T>
Field<T> boolean(std::string_view key, bool T::*m, bool fallback, std::string_view label, std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Boolean, label, "", doc, 0.0, 1.0, fallback ? 1.0 : 0.0);
  f.member = m;
  return f;
}

template <class T>
Field<T> vec3(std::string_view key, Vec3 T::*m, const Vec3& fallback, double min, double max, std::string_view unit,
              std::string_view label, std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Vec3, label, unit, doc, min, max, 0.0);
  f.fallbackVec = fallback;
  f.member = m;
  return f;
}

template <class T>
Field<T> direction(std::string_view key, Vec3 T::*m, const Vec3& fallback, std::string_view label,
                   std::string_view doc) {
  Field<T> f =
      makeField<T>(key, Kind::Direction, label, "", doc, -JsonObject::kWorldExtent, JsonObject::kWorldExtent, 0.0);
  f.fallbackVec = fallback;
  f.member = m;
  return f;
}

template <class T>
Field<T> points(std::string_view key, std::vector<Vec3> T::*m, std::string_view label, std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Points, label, "m", doc, -JsonObject::kWorldExtent, JsonObject::kWorldExtent, 0.0);
  f.member = m;
  f.required = true;
  return f;
}

template <class T>
Field<T> choice(std::string_view key, std::vector<std::string_view> options, int fallback, int (*get)(const T&),
                void (*set)(T&, int), std::string_view label, std::string_view doc) {
  Field<T> f = makeField<T>(key, Kind::Choice, label, "", doc, 0.0, double(options.size() - 1), double(fallback));
  f.choices = std::move(options);
  f.getChoice = get;
  f.setChoice = set;
  return f;
}

// --- the parts that do not depend on T ---

namespace detail {
struct Limits {
  std::string_view key;
  Kind kind;
  double min, max;
  bool required;
  std::string_view doc;
  const std::vector<std::string_view>* choices;
};
// Reads one present value; the out-parameter that matches the kind is set.
void read(JsonObject& o, const Limits& f, double* scalar, Vec3* vec, std::vector<Vec3>* points, uint64_t* seed);
// "" if the value is within the field's limits, else the reader's message for it ("must be in
// [0, 45], got 50"); `below` gets the pointer below the key ("/0" for a point, else ""). A
// float member is checked against its limits rounded to float, as read values were; an angle
// is given in radians.
std::string check(const Limits& f, double scalar, const Vec3* vec, const std::vector<Vec3>* points,
                  std::string* below);
Json write(Kind kind, double scalar, const Vec3* vec, const std::vector<Vec3>* points, const std::vector<std::string_view>* choices);
}  // namespace detail

template <class T>
detail::Limits limitsOf(const Field<T>& f) {
  return {f.key, f.kind, f.min, f.max, f.required, f.doc, &f.choices};
}

// The value of a scalar field in file units (degrees for angles; the index of a choice).
template <class T>
double fileValue(const Field<T>& f, const T& v) {
  if (f.kind == Kind::Choice) return double(f.getChoice(v));
  if (auto m = std::get_if<float T::*>(&f.member)) return f.kind == Kind::Angle ? toDegrees(v.**m) : double(v.**m);
  if (auto m = std::get_if<int T::*>(&f.member)) return double(v.**m);
  if (auto m = std::get_if<uint64_t T::*>(&f.member)) return double(v.**m);
  if (auto m = std::get_if<bool T::*>(&f.member)) return v.**m ? 1.0 : 0.0;
  return 0.0;
}

// Sets a scalar field from a value in file units (the reverse of fileValue).
template <class T>
void setFileValue(const Field<T>& f, T& v, double value) {
  if (f.kind == Kind::Choice) f.setChoice(v, int(value));
  else if (auto m = std::get_if<float T::*>(&f.member)) v.**m = f.kind == Kind::Angle ? fromDegrees(value) : float(value);
  else if (auto m = std::get_if<int T::*>(&f.member)) v.**m = int(value);
  else if (auto m = std::get_if<uint64_t T::*>(&f.member)) v.**m = uint64_t(value);
  else if (auto m = std::get_if<bool T::*>(&f.member)) v.**m = value != 0.0;
}

// Sets every field of `v` to its default.
template <class T>
void setDefaults(const Schema<T>& s, T& v) {
  for (const Field<T>& f : s.fields) {
    if (auto m = std::get_if<Vec3 T::*>(&f.member)) v.**m = f.fallbackVec;
    else if (auto m = std::get_if<std::vector<Vec3> T::*>(&f.member)) (v.**m).clear();
    else if (auto m = std::get_if<uint64_t T::*>(&f.member)) v.**m = uint64_t(f.fallback);
    else setFileValue(f, v, f.fallback);
  }
}

// Reads one field if its key is present (a required one must be); otherwise leaves v as it is.
template <class T>
void readField(JsonObject& o, const Field<T>& f, T& v) {
  if (!o.has(f.key)) {
    if (f.required) throw o.error(f.key, fmt::format("is required ({})", f.doc));
    o.markRead(f.key);  // asked for: a near miss of it is suggested
    return;
  }
  double scalar = 0.0;
  uint64_t seedValue = 0;
  Vec3 vec = Vec3::Zero();
  std::vector<Vec3> pts;
  detail::read(o, limitsOf(f), &scalar, &vec, &pts, &seedValue);
  if (auto m = std::get_if<Vec3 T::*>(&f.member)) v.**m = vec;
  else if (auto m = std::get_if<std::vector<Vec3> T::*>(&f.member)) v.**m = std::move(pts);
  else if (auto m = std::get_if<uint64_t T::*>(&f.member)) v.**m = seedValue;
  else setFileValue(f, v, scalar);
}

// The keys `o` has, read over `v`. Does not finish `o`.
template <class T>
void readOver(JsonObject& o, const Schema<T>& s, T& v) {
  for (const Field<T>& f : s.fields) readField(o, f, v);
}

// The defaults, overridden by the keys `o` has. Does not finish `o`.
template <class T>
T read(JsonObject& o, const Schema<T>& s) {
  T v{};
  setDefaults(s, v);
  readOver(o, s, v);
  return v;
}

// Every field of `v` as JSON (what read() gives back exactly).
template <class T>
Json write(const Schema<T>& s, const T& v) {
  Json j = Json::object();
  for (const Field<T>& f : s.fields) {
    if (auto m = std::get_if<Vec3 T::*>(&f.member)) j[std::string(f.key)] = detail::write(f.kind, 0.0, &(v.**m), nullptr, nullptr);
    else if (auto m = std::get_if<std::vector<Vec3> T::*>(&f.member)) j[std::string(f.key)] = detail::write(f.kind, 0.0, nullptr, &(v.**m), nullptr);
    else if (auto m = std::get_if<uint64_t T::*>(&f.member)) j[std::string(f.key)] = v.**m;
    else if (auto m = std::get_if<float T::*>(&f.member); m && f.kind == Kind::Number) j[std::string(f.key)] = v.**m;
    else j[std::string(f.key)] = detail::write(f.kind, fileValue(f, v), nullptr, nullptr, &f.choices);
  }
  return j;
}

// A value that did not come from JSON (a saved state, a widget, code) checked against the
// readers' limits: nullopt when every field is within them, else "/<key>[/i]: <the reader's
// message>" for the first field that is not.
template <class T>
std::optional<std::string> check(const Schema<T>& s, const T& v) {
  for (const Field<T>& f : s.fields) {
    std::string below, message;
    if (auto m = std::get_if<Vec3 T::*>(&f.member)) message = detail::check(limitsOf(f), 0.0, &(v.**m), nullptr, &below);
    else if (auto m = std::get_if<std::vector<Vec3> T::*>(&f.member))
      message = detail::check(limitsOf(f), 0.0, nullptr, &(v.**m), &below);
    else if (auto m = std::get_if<uint64_t T::*>(&f.member)) message = detail::check(limitsOf(f), double(v.**m), nullptr, nullptr, &below);
    else if (auto m = std::get_if<float T::*>(&f.member))  // angles are checked in radians
      message = detail::check(limitsOf(f), double(v.**m), nullptr, nullptr, &below);
    else message = detail::check(limitsOf(f), fileValue(f, v), nullptr, nullptr, &below);
    if (!message.empty()) return "/" + jsonPointerEscape(f.key) + below + ": " + message;
  }
  return std::nullopt;
}

}  // namespace tendril::schema
