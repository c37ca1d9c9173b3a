// JSON writing and the top-level field reader (see json.hpp).
#include "io/json.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace dpts::io {

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (c == '\n') {
      out += "\\n";
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

JsonObject& JsonObject::raw(const std::string& key, const std::string& json) {
  if (body_.size() > 1) body_ += ',';
  body_ += json_string(key) + ":" + json;
  return *this;
}

JsonObject& JsonObject::add(const std::string& key, const std::string& value) {
  return raw(key, json_string(value));
}
JsonObject& JsonObject::add(const std::string& key, double value) {
  return raw(key, json_number(value));
}
JsonObject& JsonObject::add(const std::string& key, long long value) {
  return raw(key, std::to_string(value));
}
JsonObject& JsonObject::add(const std::string& key, unsigned long long value) {
  return raw(key, std::to_string(value));
}
JsonObject& JsonObject::add(const std::string& key, bool value) {
  return raw(key, value ? "true" : "false");
}

namespace {

// End of the JSON value starting at json[i] (one past it), or npos when malformed.
std::size_t value_end(const std::string& json, std::size_t i) {
  if (i >= json.size()) return std::string::npos;
  if (json[i] == '"') {
    for (++i; i < json.size(); ++i) {
      if (json[i] == '\\') {
        ++i;
      } else if (json[i] == '"') {
        return i + 1;
      }
    }
    return std::string::npos;
  }
  if (json[i] == '{' || json[i] == '[') {
    int depth = 0;
    for (; i < json.size(); ++i) {
      if (json[i] == '"') {
        i = value_end(json, i);
        if (i == std::string::npos) return i;
        --i;
      } else if (json[i] == '{' || json[i] == '[') {
        ++depth;
      } else if (json[i] == '}' || json[i] == ']') {
        if (--depth == 0) return i + 1;
      }
    }
    return std::string::npos;
  }
  while (i < json.size() && json[i] != ',' && json[i] != '}' && json[i] != ']') ++i;
  return i;
}

std::string unescape(const std::string& s) {
  std::string out;
  for (std::size_t i = 1; i + 1 < s.size(); ++i) {
    if (s[i] != '\\' || i + 2 >= s.size()) {
      out += s[i];
      continue;
    }
    const char e = s[++i];
    if (e == 'n') {
      out += '\n';
    } else if (e == 'u' && i + 4 < s.size()) {
      unsigned code = 0;
      std::from_chars(s.data() + i + 1, s.data() + i + 5, code, 16);
      out += static_cast<char>(code);
      i += 4;
    } else {
      out += e;
    }
  }
  return out;
}

}  // namespace

std::optional<std::string> json_field(const std::string& json, const std::string& key) {
  // Walk the top-level object: "key":value pairs separated by commas.
  std::size_t i = json.find('{');
  if (i == std::string::npos) return std::nullopt;
  ++i;
  while (i < json.size()) {
    while (i < json.size() && (json[i] == ' ' || json[i] == '\n' || json[i] == ',')) ++i;
    if (i >= json.size() || json[i] != '"') return std::nullopt;
    const std::size_t key_end = value_end(json, i);
    if (key_end == std::string::npos || key_end >= json.size() || json[key_end] != ':') {
      return std::nullopt;
    }
    const std::string name = unescape(json.substr(i, key_end - i));
    const std::size_t v = key_end + 1, end = value_end(json, v);
    if (end == std::string::npos) return std::nullopt;
    if (name == key) {
      const std::string value = json.substr(v, end - v);
      return json[v] == '"' ? unescape(value) : value;
    }
    i = end;
  }
  return std::nullopt;
}

}  // namespace dpts::io
