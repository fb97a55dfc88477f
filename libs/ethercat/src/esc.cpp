#include "concert/ethercat/esc.hpp"

#include <array>
#include <cstdio>
#include <utility>

namespace concert::ethercat::esc {

uint8_t open_ports(uint16_t dl_status) {
  uint8_t mask = 0;
  for (int p = 0; p < 4; ++p) {
    const bool open = (dl_status & dl_loop_closed(p)) == 0;
    const bool communicating = (dl_status & dl_communication(p)) != 0;
    if (open && communicating) mask = static_cast<uint8_t>(mask | (1U << p));
  }
  return mask;
}

uint8_t linked_ports(uint16_t dl_status) { return static_cast<uint8_t>((dl_status >> 4) & 0x0F); }

std::string to_string(AlState state) {
  switch (state) {
    case AlState::kInit: return "INIT";
    case AlState::kPreOp: return "PRE-OP";
    case AlState::kBoot: return "BOOT";
    case AlState::kSafeOp: return "SAFE-OP";
    case AlState::kOp: return "OP";
  }
  char text[16];
  std::snprintf(text, sizeof text, "state 0x%X", static_cast<unsigned>(state));
  return text;
}

std::optional<AlState> al_state_from(uint16_t value) {
  switch (value & kAlStateMask) {
    case 1: return AlState::kInit;
    case 2: return AlState::kPreOp;
    case 3: return AlState::kBoot;
    case 4: return AlState::kSafeOp;
    case 8: return AlState::kOp;
    default: return std::nullopt;
  }
}

std::string al_status_code_name(uint16_t code) {
  // ETG.1000.6, "AL Status Codes".
  static constexpr std::array<std::pair<uint16_t, const char*>, 50> kNames{{
      {0x0000, "no error"},
      {0x0001, "unspecified error"},
      {0x0002, "no memory"},
      {0x0011, "invalid requested state change"},
      {0x0012, "unknown requested state"},
      {0x0013, "bootstrap not supported"},
      {0x0014, "no valid firmware"},
      {0x0015, "invalid mailbox configuration (BOOT)"},
      {0x0016, "invalid mailbox configuration (PRE-OP)"},
      {0x0017, "invalid sync manager configuration"},
      {0x0018, "no valid inputs available"},
      {0x0019, "no valid outputs"},
      {0x001A, "synchronization error"},
      {0x001B, "sync manager watchdog"},
      {0x001C, "invalid sync manager types"},
      {0x001D, "invalid output configuration"},
      {0x001E, "invalid input configuration"},
      {0x001F, "invalid watchdog configuration"},
      {0x0020, "slave needs cold start"},
      {0x0021, "slave needs INIT"},
      {0x0022, "slave needs PRE-OP"},
      {0x0023, "slave needs SAFE-OP"},
      {0x0024, "invalid input mapping"},
      {0x0025, "invalid output mapping"},
      {0x0026, "inconsistent settings"},
      {0x0027, "free run not supported"},
      {0x0028, "sync mode not supported"},
      {0x0029, "free run needs 3-buffer mode"},
      {0x002A, "background watchdog"},
      {0x002B, "no valid inputs and outputs"},
      {0x002C, "fatal sync error"},
      {0x002D, "no sync error"},
      {0x0030, "invalid DC SYNC configuration"},
      {0x0031, "invalid DC latch configuration"},
      {0x0032, "PLL error"},
      {0x0033, "DC sync IO error"},
      {0x0034, "DC sync timeout error"},
      {0x0035, "DC invalid sync cycle time"},
      {0x0036, "DC sync0 cycle time"},
      {0x0037, "DC sync1 cycle time"},
      {0x0041, "mailbox AoE"},
      {0x0042, "mailbox EoE"},
      {0x0043, "mailbox CoE"},
      {0x0044, "mailbox FoE"},
      {0x0045, "mailbox SoE"},
      {0x004F, "mailbox VoE"},
      {0x0050, "EEPROM no access"},
      {0x0051, "EEPROM error"},
      {0x0060, "slave restarted locally"},
      {0x0061, "device identification value updated"},
  }};
  for (const auto& [value, name] : kNames) {
    if (value == code) return name;
  }
  char text[40];
  std::snprintf(text, sizeof text, "unknown AL status code 0x%04X", code);
  return text;
}

}  // namespace concert::ethercat::esc
