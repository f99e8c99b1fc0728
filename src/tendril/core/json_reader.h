// Strict reading of JSON input files (scenes, species, graphs, edit scripts).
//
// Every value is read through a JsonObject, which knows the file and the JSON pointer of the
// object it views. A wrong type or an out-of-range value is an Error naming both; finish()
// reports any key that was never read — typos are the most common user bug — with a
// "did you mean" suggestion.
#pragma once

#include "tendril/core/error.h"
#include "tendril/core/math.h"

#include <nlohmann/json_fwd.hpp>

#include <filesystem>
#include <initializer_list>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace tendril {

using Json = nlohmann::json;

// Parses text as JSON; a syntax error becomes Error(source, "line:column", what was wrong).
Json parseJson(std::string_view text, const std::string& source);
// Reads and parses a file; an unreadable file is an Error naming its path.
Json readJsonFile(const std::filesystem::path& path);

// Escapes a key for use in a JSON pointer (RFC 6901).
std::string jsonPointerEscape(std::string_view key);
// A short, one-line description of a JSON value for error messages, e.g. `string "abc"`.
std::string describeJson(const Json& value);

class JsonObject {
 public:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  // Coordinates, sizes and offsets without a range of their own stay within this of the origin:
  // 100 km (floats keep millimetres there; much beyond, the simulations' cell indices overflow).
  static constexpr double kWorldExtent = 1e5;

  // `json` must outlive this view. Throws Error if it is not an object.
  JsonObject(const Json& json, std::string source, std::string pointer = "");
  JsonObject(JsonObject&&) noexcept;
  JsonObject& operator=(JsonObject&&) noexcept;
  ~JsonObject();

  const std::string& source() const { return source_; }
  const std::string& pointer() const { return pointer_; }
  std::string pointerTo(std::string_view key) const;
  const Json& json() const { return *json_; }

  bool has(std::string_view key) const;
  // The value at key (marking it read), or nullptr.
  const Json* find(std::string_view key);
  // Marks a key as read without interpreting it (for values read by other code).
  void markRead(std::string_view key);

  double number(std::string_view key, double fallback, double min = -kInf, double max = kInf);
  double requiredNumber(std::string_view key, double min = -kInf, double max = kInf);
  float numberf(std::string_view key, float fallback, double min = -kInf, double max = kInf) {
    return static_cast<float>(number(key, fallback, min, max));
  }
  int64_t integer(std::string_view key, int64_t fallback, int64_t min, int64_t max);
  // A non-negative integer up to 2^53 (JSON's exact integer range).
  uint64_t seed(std::string_view key, uint64_t fallback);
  bool boolean(std::string_view key, bool fallback);
  std::string string(std::string_view key, std::string fallback);
  std::string requiredString(std::string_view key);
  // One of `options`; anything else lists them in the error.
  std::string choice(std::string_view key, std::string fallback,
                     std::initializer_list<std::string_view> options);
  Vec2 vec2(std::string_view key, const Vec2& fallback, double min = -kWorldExtent, double max = kWorldExtent);
  Vec3 vec3(std::string_view key, const Vec3& fallback, double min = -kWorldExtent, double max = kWorldExtent);
  Vec3 requiredVec3(std::string_view key);
  // A non-zero 3-vector, returned normalised.
  Vec3 direction(std::string_view key, const Vec3& fallback);
  // An angle given in degrees in the file, returned in radians.
  float angle(std::string_view key, float fallbackDegrees, double minDegrees, double maxDegrees);
  std::vector<float> numberArray(std::string_view key, double min = -kInf, double max = kInf);

  JsonObject object(std::string_view key);
  std::optional<JsonObject> optionalObject(std::string_view key);
  // The objects of an array (empty when the key is absent).
  std::vector<JsonObject> objectArray(std::string_view key);

  // Errors located at a key of this object, or at the object itself.
  Error error(std::string_view key, const std::string& message) const;
  Error error(const std::string& message) const;

  // Throws on the first key that was never read. Call once every known key has been read.
  void finish();

 private:
  const Json& at(std::string_view key) const;
  Vec3 parseVec3(std::string_view key, const Json& v, double min, double max) const;

  const Json* json_;
  std::string source_;
  std::string pointer_;
  std::set<std::string, std::less<>> read_;   // keys present and read
  std::set<std::string, std::less<>> asked_;  // every key asked for, present or not
  bool finished_ = false;
  uint64_t errorsAtStart_ = 0;  // Error::createdOnThisThread() when constructed
};

// Levenshtein distance, for "did you mean" suggestions.
size_t editDistance(std::string_view a, std::string_view b);

}  // namespace tendril
