// Parameters of the testbed's options structs. Each has one spec (its YAML
// key, meaning and range), written once beside the options it belongs to;
// the options' Check() and the configuration reader both check against it,
// so they never disagree. A parameter's default is its options struct's
// member initializer, and nothing else.
#pragma once

#include <string>

namespace rig {

/// One parameter. Numbers lie in [lo, hi] (whole-number fields must also be
/// whole); text is one of `choices` (null-terminated), or any text when
/// `choices` is null; true/false parameters have no range.
struct ParamSpec {
  const char* key;  ///< YAML key, "section.name": what every message names
  const char* doc;  ///< meaning, with units
  double lo = 0, hi = 0;
  const char* const* choices = nullptr;
};

/// Throws InputError "key 'K': V is out of range [lo, hi]" unless
/// lo <= value <= hi (NaN is never in range).
void CheckParam(const ParamSpec& spec, double value);

/// Throws InputError "key 'K': 'V' is not one of a, b" unless `value` is one
/// of spec.choices (any text passes when there are none).
void CheckParam(const ParamSpec& spec, const std::string& value);

/// "[lo, hi]", "one of a, b", "any text" or "true or false" (`boolean`).
std::string RangeText(const ParamSpec& spec, bool boolean = false);

/// A number as the shortest text that reads back to it ("0.06", "1e+06").
std::string FormatParamNumber(double value);

}  // namespace rig
