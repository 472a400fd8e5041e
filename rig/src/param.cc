#include "rig/param.h"

#include <charconv>
#include <cstring>

#include "rig/input_file.h"

namespace rig {

std::string FormatParamNumber(double value) {
  char text[64];
  const auto r = std::to_chars(text, text + sizeof text, value);
  return std::string(text, r.ptr);
}

std::string RangeText(const ParamSpec& spec, bool boolean) {
  if (boolean) return "true or false";
  if (spec.choices) {
    std::string s = "one of";
    for (const char* const* c = spec.choices; *c; ++c)
      s += std::string(c == spec.choices ? " " : ", ") + *c;
    return s;
  }
  return "[" + FormatParamNumber(spec.lo) + ", " + FormatParamNumber(spec.hi) + "]";
}

void CheckParam(const ParamSpec& spec, double value) {
  if (!(value >= spec.lo && value <= spec.hi))
    throw InputError(std::string("key '") + spec.key + "': " + FormatParamNumber(value) +
                     " is out of range " + RangeText(spec));
}

void CheckParam(const ParamSpec& spec, const std::string& value) {
  if (!spec.choices) return;
  for (const char* const* c = spec.choices; *c; ++c)
    if (value == *c) return;
  throw InputError(std::string("key '") + spec.key + "': '" + ClipForMessage(value) + "' is not " +
                   RangeText(spec));
}

}  // namespace rig
