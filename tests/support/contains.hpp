// Whether a message names what a test expects it to: the tests check what an error or event says.
#pragma once

#include <string_view>

namespace fba::test {

inline bool contains(std::string_view text, std::string_view part) { return text.find(part) != std::string_view::npos; }

}  // namespace fba::test
