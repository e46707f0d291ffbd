// A pseudo-terminal pair (posix_openpt) for a device emulator: the emulator owns the master end and
// a driver opens `slave_path` as it would /dev/ttyUSB0.
#pragma once

#include <string>

#include "fba/can/fd.hpp"

namespace fba::can {

struct Pty {
  Fd master;
  // The emulator keeps the slave end open too: with no slave open, the master reads EIO, so a
  // driver that opens, closes and reopens the line would find the emulator gone.
  Fd slave;
  std::string slave_path;
};

// A raw (no echo, no line editing) pseudo-terminal; throws BusError with the reason.
Pty open_pty();

}  // namespace fba::can
