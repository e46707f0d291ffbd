#include "fba/can/pty.hpp"

#include <fcntl.h>
#include <stdlib.h>
#include <termios.h>

#include <cerrno>
#include <cstring>

#include "fba/can/bus.hpp"

namespace fba::can {

Pty open_pty() {
  Pty pty;
  pty.master.reset(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!pty.master) throw BusError(std::string("posix_openpt failed: ") + std::strerror(errno));
  if (::grantpt(pty.master.get()) != 0 || ::unlockpt(pty.master.get()) != 0)
    throw BusError(std::string("cannot unlock the pseudo-terminal: ") + std::strerror(errno));
  char name[128];
  if (::ptsname_r(pty.master.get(), name, sizeof name) != 0)
    throw BusError(std::string("ptsname failed: ") + std::strerror(errno));
  pty.slave_path = name;
  pty.slave.reset(::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!pty.slave)
    throw BusError(pty.slave_path + ": cannot open the pseudo-terminal's slave end: " + std::strerror(errno));
  termios tio{};
  if (::tcgetattr(pty.slave.get(), &tio) != 0)
    throw BusError(pty.slave_path + ": tcgetattr failed: " + std::strerror(errno));
  ::cfmakeraw(&tio);
  if (::tcsetattr(pty.slave.get(), TCSANOW, &tio) != 0)
    throw BusError(pty.slave_path + ": tcsetattr failed: " + std::strerror(errno));
  return pty;
}

}  // namespace fba::can
