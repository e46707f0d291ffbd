// Text for messages to a person: what comes from outside the program shown safely, and numbers
// shown exactly.
#pragma once

#include <string>

namespace fba {

// Text from outside the program (a task file, a component's exception, an event's payload) as a
// terminal may show it: newline, tab and CR written as \n, \t and \r, other control bytes (NUL,
// ESC...) as \xNN, so that none can move the cursor, clear the screen or split one message into two
// lines, and a name with a newline reads as the name it is; every other byte as it is.
std::string escape_controls(const std::string& s);

// The shortest text that reads back as the same double, whole numbers as such: a value just
// outside a range never looks like the limit itself ("found 1000001", not "1e+06" or "1000001.000000").
std::string number_text(double d);

}  // namespace fba
