// Minimal JSON for run reports and dpts-eval: writing objects, and reading back top-level
// fields of the reports dpts writes itself (not a general parser).
#pragma once

#include <optional>
#include <string>

namespace dpts::io {

// A JSON string literal: quotes, backslash escapes, control characters as \u00XX.
std::string json_string(const std::string& s);

// A JSON number (shortest round-trip form), or null when not finite.
std::string json_number(double v);

// Builds one JSON object: add fields in order, then str(). Values given as raw JSON text
// (raw) are inserted as they are (nested objects and arrays built by another writer).
class JsonObject {
 public:
  JsonObject& add(const std::string& key, const std::string& value);  // a string
  JsonObject& add(const std::string& key, const char* value) { return add(key, std::string(value)); }
  JsonObject& add(const std::string& key, double value);
  JsonObject& add(const std::string& key, long long value);
  JsonObject& add(const std::string& key, unsigned long long value);
  JsonObject& add(const std::string& key, int value) { return add(key, static_cast<long long>(value)); }
  JsonObject& add(const std::string& key, std::size_t value) {
    return add(key, static_cast<unsigned long long>(value));
  }
  JsonObject& add(const std::string& key, bool value);
  JsonObject& raw(const std::string& key, const std::string& json);
  std::string str() const { return body_ + "}"; }

 private:
  std::string body_ = "{";
};

// Builds one JSON array: raw JSON values (objects from JsonObject) or strings, in order.
class JsonArray {
 public:
  JsonArray& raw(const std::string& json) {
    body_ += (body_.size() > 1 ? "," : "") + json;
    return *this;
  }
  JsonArray& add(const std::string& value) { return raw(json_string(value)); }
  std::string str() const { return body_ + "]"; }

 private:
  std::string body_ = "[";
};

// The value of a top-level field `key` of a JSON object written by JsonObject: a string
// field unescaped, any other value as its raw text. nullopt when absent or malformed.
std::optional<std::string> json_field(const std::string& json, const std::string& key);

}  // namespace dpts::io
