// Scalars for the YAML files we write by hand (model, scenario and effects files), spelled so
// that reading the file back gives the same values: numbers with every digit, free text quoted.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace selfcal::yaml {

// %.17g: a double reads back bit for bit.
std::string Number(double value);

// A flow sequence of numbers: [1, 2.5, -3].
std::string NumberList(const std::vector<double>& values);

// Free text (names, paths) as a scalar that reads back unchanged, also inside a flow map: plain
// when it is made of letters, digits and _ . / + - only (iiwa14, /etc/selfcal/x.yaml), else
// double-quoted with escapes ('#', ': ', ', ', quotes, spaces, control characters, "null").
std::string Text(std::string_view text);

}  // namespace selfcal::yaml
