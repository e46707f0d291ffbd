// Text from outside the program (a task file, a component's exception, an event's payload) as a
// terminal may show it.
#pragma once

#include <string>

namespace fba {

// Control bytes (NUL, ESC, CR, newline...) written as \xNN, so that none can move the cursor,
// clear the screen or split one message into two lines; every other byte as it is.
std::string escape_controls(const std::string& s);

}  // namespace fba
