#include "tendril/core/json_reader.h"

#include "tendril/core/schema.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cassert>
#include <cmath>
#include <exception>
#include <fstream>
#include <sstream>

namespace tendril {

namespace {

// nlohmann reports the byte offset of a syntax error; users want line and column.
std::string lineColumn(std::string_view text, size_t byte) {
  size_t line = 1, column = 1;
  for (size_t i = 0; i < text.size() && i + 1 < byte; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return fmt::format("{}:{}", line, column);
}

// Drops nlohmann's "[json.exception.parse_error.101] parse error at line 1, column 2: " prefix.
std::string stripParsePrefix(std::string message) {
  size_t p = message.find(": ");
  if (message.rfind("[json.exception", 0) == 0 && p != std::string::npos)
    return message.substr(p + 2);
  return message;
}

}  // namespace

Json parseJson(std::string_view text, const std::string& source) {
  try {
    return Json::parse(text.begin(), text.end());
  } catch (const Json::parse_error& e) {
    throw Error(source, lineColumn(text, e.byte), stripParsePrefix(e.what()));
  } catch (const Json::exception& e) {
    // A number too large for a double ("number overflow parsing '1e999'"): nlohmann gives no
    // position, so the place is where the quoted token first occurs.
    const std::string message = stripParsePrefix(e.what());
    const size_t open = message.find('\''), close = message.rfind('\'');
    size_t at = std::string_view::npos;
    if (open != std::string::npos && close > open + 1) at = text.find(message.substr(open + 1, close - open - 1));
    throw Error(source, at == std::string_view::npos ? std::string() : lineColumn(text, at + 1), message);
  }
}

Json readJsonFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string(), "", "cannot open file for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw Error(path.string(), "", "cannot read file");
  return parseJson(ss.str(), path.string());
}

std::string jsonPointerEscape(std::string_view key) {
  std::string out;
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

std::string describeJson(const Json& v) {
  std::string text = v.dump();
  if (text.size() > 40) text = text.substr(0, 37) + "...";
  switch (v.type()) {
    case Json::value_t::null: return "null";
    case Json::value_t::boolean: return "boolean " + text;
    case Json::value_t::string: return "string " + text;
    case Json::value_t::number_integer:
    case Json::value_t::number_unsigned:
    case Json::value_t::number_float: return "number " + text;
    case Json::value_t::array: return "an array";
    case Json::value_t::object: return "an object";
    default: return text;
  }
}

size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

JsonObject::JsonObject(const Json& json, std::string source, std::string pointer)
    : json_(&json), source_(std::move(source)), pointer_(std::move(pointer)),
      errorsAtStart_(Error::createdOnThisThread()) {
  if (!json.is_object())
    throw Error(source_, pointer_.empty() ? "/" : pointer_,
                "expected an object, got " + describeJson(json));
}

JsonObject::JsonObject(JsonObject&& o) noexcept
    : json_(o.json_),
      source_(std::move(o.source_)),
      pointer_(std::move(o.pointer_)),
      read_(std::move(o.read_)),
      asked_(std::move(o.asked_)),
      finished_(o.finished_),
      errorsAtStart_(o.errorsAtStart_) {
  o.finished_ = true;
}

JsonObject& JsonObject::operator=(JsonObject&& o) noexcept {
  json_ = o.json_;
  source_ = std::move(o.source_);
  pointer_ = std::move(o.pointer_);
  read_ = std::move(o.read_);
  asked_ = std::move(o.asked_);
  finished_ = o.finished_;
  errorsAtStart_ = o.errorsAtStart_;
  o.finished_ = true;
  return *this;
}

JsonObject::~JsonObject() {
  // Every reader must call finish(): otherwise unknown keys would pass silently. Reading that
  // stopped at an Error (in flight, or raised and already handled) is exempt.
  assert((finished_ || std::uncaught_exceptions() > 0 || Error::createdOnThisThread() != errorsAtStart_) &&
         "JsonObject::finish() was not called");
}

std::string JsonObject::pointerTo(std::string_view key) const {
  return pointer_ + "/" + jsonPointerEscape(key);
}

bool JsonObject::has(std::string_view key) const { return json_->contains(key); }

const Json& JsonObject::at(std::string_view key) const { return json_->find(key).value(); }

const Json* JsonObject::find(std::string_view key) {
  asked_.emplace(key);
  auto it = json_->find(key);
  if (it == json_->end()) return nullptr;
  read_.emplace(key);
  return &it.value();
}

void JsonObject::markRead(std::string_view key) {
  asked_.emplace(key);
  if (json_->contains(key)) read_.emplace(key);
}

Error JsonObject::error(std::string_view key, const std::string& message) const {
  return Error(source_, pointerTo(key), message);
}

Error JsonObject::error(const std::string& message) const {
  return Error(source_, pointer_.empty() ? "/" : pointer_, message);
}

double JsonObject::number(std::string_view key, double fallback, double min, double max) {
  const Json* v = find(key);
  if (!v) return fallback;
  if (!v->is_number()) throw error(key, "expected a number, got " + describeJson(*v));
  double d = v->get<double>();
  if (!std::isfinite(d) || d < min || d > max)
    throw error(key, fmt::format("must be {}, got {}", schema::rangeText(min, max), v->dump()));
  return d;
}

double JsonObject::requiredNumber(std::string_view key, double min, double max) {
  if (!has(key)) throw error(key, "is required (a number)");
  return number(key, 0.0, min, max);
}

int64_t JsonObject::integer(std::string_view key, int64_t fallback, int64_t min, int64_t max) {
  const Json* v = find(key);
  if (!v) return fallback;
  bool integral = v->is_number_integer() ||
                  (v->is_number_float() && std::floor(v->get<double>()) == v->get<double>() &&
                   std::abs(v->get<double>()) < 9.007199254740992e15);
  if (!integral) throw error(key, "expected an integer, got " + describeJson(*v));
  int64_t i;
  if (v->is_number_unsigned())
    i = static_cast<int64_t>(std::min<uint64_t>(v->get<uint64_t>(), INT64_MAX));
  else if (v->is_number_integer())
    i = v->get<int64_t>();
  else
    i = static_cast<int64_t>(v->get<double>());
  if (i < min || i > max)
    throw error(key, fmt::format("must be in [{}, {}], got {}", min, max, v->dump()));
  return i;
}

uint64_t JsonObject::seed(std::string_view key, uint64_t fallback) {
  return static_cast<uint64_t>(
      integer(key, static_cast<int64_t>(fallback), 0, int64_t(1) << 53));
}

bool JsonObject::boolean(std::string_view key, bool fallback) {
  const Json* v = find(key);
  if (!v) return fallback;
  if (!v->is_boolean()) throw error(key, "expected true or false, got " + describeJson(*v));
  return v->get<bool>();
}

std::string JsonObject::string(std::string_view key, std::string fallback) {
  const Json* v = find(key);
  if (!v) return fallback;
  if (!v->is_string()) throw error(key, "expected a string, got " + describeJson(*v));
  return v->get<std::string>();
}

std::string JsonObject::requiredString(std::string_view key) {
  if (!has(key)) throw error(key, "is required (a string)");
  return string(key, "");
}

std::string JsonObject::choice(std::string_view key, std::string fallback,
                               std::initializer_list<std::string_view> options) {
  std::string s = string(key, fallback);
  if (!has(key)) return s;
  for (auto o : options)
    if (o == s) return s;
  std::string list;
  for (auto o : options) list += (list.empty() ? "\"" : ", \"") + std::string(o) + "\"";
  throw error(key, fmt::format("must be one of {}, got \"{}\"", list, s));
}

Vec3 JsonObject::parseVec3(std::string_view key, const Json& v, double min, double max) const {
  if (!v.is_array() || v.size() != 3)
    throw error(key, "expected an array of 3 numbers, got " + describeJson(v));
  Vec3 out;
  for (int i = 0; i < 3; ++i) {
    if (!v[i].is_number())
      throw Error(source_, pointerTo(key) + "/" + std::to_string(i),
                  "expected a number, got " + describeJson(v[i]));
    double d = v[i].get<double>();
    if (!std::isfinite(d) || d < min || d > max)
      throw Error(source_, pointerTo(key) + "/" + std::to_string(i),
                  fmt::format("must be {}, got {}", schema::rangeText(min, max), v[i].dump()));
    out[i] = static_cast<float>(d);
  }
  return out;
}

Vec3 JsonObject::vec3(std::string_view key, const Vec3& fallback, double min, double max) {
  const Json* v = find(key);
  if (!v) return fallback;
  return parseVec3(key, *v, min, max);
}

Vec3 JsonObject::requiredVec3(std::string_view key) {
  if (!has(key)) throw error(key, "is required (an array of 3 numbers)");
  return vec3(key, Vec3::Zero());
}

Vec2 JsonObject::vec2(std::string_view key, const Vec2& fallback, double min, double max) {
  const Json* v = find(key);
  if (!v) return fallback;
  if (!v->is_array() || v->size() != 2)
    throw error(key, "expected an array of 2 numbers, got " + describeJson(*v));
  Vec2 out;
  for (int i = 0; i < 2; ++i) {
    const Json& e = (*v)[i];
    std::string p = pointerTo(key) + "/" + std::to_string(i);
    if (!e.is_number()) throw Error(source_, p, "expected a number, got " + describeJson(e));
    double d = e.get<double>();
    if (!std::isfinite(d) || d < min || d > max)
      throw Error(source_, p, fmt::format("must be {}, got {}", schema::rangeText(min, max), e.dump()));
    out[i] = static_cast<float>(d);
  }
  return out;
}

Vec3 JsonObject::direction(std::string_view key, const Vec3& fallback) {
  Vec3 d = vec3(key, fallback);
  if (!(d.norm() > 1e-6f)) throw error(key, "must be a non-zero direction");
  return d.normalized();
}

float JsonObject::angle(std::string_view key, float fallbackDegrees, double minDegrees,
                        double maxDegrees) {
  return radians(static_cast<float>(number(key, fallbackDegrees, minDegrees, maxDegrees)));
}

std::vector<float> JsonObject::numberArray(std::string_view key, double min, double max) {
  std::vector<float> out;
  const Json* v = find(key);
  if (!v) return out;
  if (!v->is_array()) throw error(key, "expected an array of numbers, got " + describeJson(*v));
  for (size_t i = 0; i < v->size(); ++i) {
    const Json& e = (*v)[i];
    std::string p = pointerTo(key) + "/" + std::to_string(i);
    if (!e.is_number()) throw Error(source_, p, "expected a number, got " + describeJson(e));
    double d = e.get<double>();
    if (!std::isfinite(d) || d < min || d > max)
      throw Error(source_, p, fmt::format("must be {}, got {}", schema::rangeText(min, max), e.dump()));
    out.push_back(static_cast<float>(d));
  }
  return out;
}

JsonObject JsonObject::object(std::string_view key) {
  const Json* v = find(key);
  if (!v) throw error(key, "is required (an object)");
  return JsonObject(*v, source_, pointerTo(key));
}

std::optional<JsonObject> JsonObject::optionalObject(std::string_view key) {
  const Json* v = find(key);
  if (!v) return std::nullopt;
  return JsonObject(*v, source_, pointerTo(key));
}

std::vector<JsonObject> JsonObject::objectArray(std::string_view key) {
  std::vector<JsonObject> out;
  const Json* v = find(key);
  if (!v) return out;
  if (!v->is_array()) throw error(key, "expected an array of objects, got " + describeJson(*v));
  out.reserve(v->size());
  for (size_t i = 0; i < v->size(); ++i)
    out.emplace_back((*v)[i], source_, pointerTo(key) + "/" + std::to_string(i));
  return out;
}

void JsonObject::finish() {
  finished_ = true;
  for (auto it = json_->begin(); it != json_->end(); ++it) {
    if (read_.count(it.key())) continue;
    // Suggest the closest key this object asked for that the file does not have.
    std::string best;
    size_t bestDistance = 3;
    for (const auto& known : asked_) {
      if (json_->contains(known)) continue;
      size_t d = editDistance(it.key(), known);
      if (d < bestDistance) {
        bestDistance = d;
        best = known;
      }
    }
    std::string message = fmt::format("unknown key \"{}\"", it.key());
    if (!best.empty()) message += fmt::format(" (did you mean \"{}\"?)", best);
    throw Error(source_, pointerTo(it.key()), message);
  }
}

}  // namespace tendril
