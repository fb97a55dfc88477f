#pragma once
// The ESC register map the master and the virtual ring share (Beckhoff "EtherCAT Slave
// Controller, Section II: Register Description", the same map on ET1100, ET1200 and the IP
// cores; ETG.1000.4 for the AL states and status codes, ETG.2010 for the SII EEPROM layout).

#include <cstdint>
#include <optional>
#include <string>

namespace concert::ethercat::esc {

// ESC information (read-only).
inline constexpr uint16_t kType = 0x0000;            ///< 1 byte: 0x11 ET1100, 0x12 ET1200, ...
inline constexpr uint16_t kRevision = 0x0001;
inline constexpr uint16_t kBuild = 0x0002;           ///< 2 bytes
inline constexpr uint16_t kFmmusSupported = 0x0004;
inline constexpr uint16_t kSyncManagersSupported = 0x0005;
inline constexpr uint16_t kRamSize = 0x0006;         ///< process data RAM in KiB
inline constexpr uint16_t kPortDescriptor = 0x0007;  ///< 2 bits per port: 00 none, 10 EBUS, 11 MII
inline constexpr uint16_t kFeatures = 0x0008;        ///< 2 bytes
// Station address.
inline constexpr uint16_t kStationAddress = 0x0010;  ///< configured station address (master sets)
inline constexpr uint16_t kStationAlias = 0x0012;
// Data link layer.
inline constexpr uint16_t kDlControl = 0x0100;       ///< 4 bytes: loop control per port
inline constexpr uint16_t kDlStatus = 0x0110;        ///< 2 bytes, bits below
// Application layer.
inline constexpr uint16_t kAlControl = 0x0120;       ///< 2 bytes: requested state | ack
inline constexpr uint16_t kAlStatus = 0x0130;        ///< 2 bytes: state | error
inline constexpr uint16_t kAlStatusCode = 0x0134;    ///< 2 bytes (ETG.1000.6 table 11)
// Watchdogs and error counters.
inline constexpr uint16_t kRxErrorCounters = 0x0300;  ///< 8 bytes, per port: invalid frame, RX error
inline constexpr uint16_t kLostLinkCounters = 0x0310; ///< 4 bytes, one per port
// SII EEPROM interface.
inline constexpr uint16_t kEepromConfig = 0x0500;    ///< bit 0: EEPROM offered to the PDI
inline constexpr uint16_t kEepromPdiAccess = 0x0501;
inline constexpr uint16_t kEepromControl = 0x0502;   ///< 2 bytes: command and status, bits below
inline constexpr uint16_t kEepromAddress = 0x0504;   ///< 4 bytes: word address
inline constexpr uint16_t kEepromData = 0x0508;      ///< 4 or 8 bytes read, 2 bytes written
// Memory configuration.
inline constexpr uint16_t kFmmu = 0x0600;            ///< 16 FMMUs of 16 bytes
inline constexpr uint16_t kSyncManager = 0x0800;     ///< 16 sync managers of 8 bytes
// Distributed clocks.
inline constexpr uint16_t kDcReceiveTimePort0 = 0x0900;  ///< 4 x 4 bytes; a write latches all ports
inline constexpr uint16_t kDcSystemTime = 0x0910;        ///< 8 bytes
inline constexpr uint16_t kDcReceiveTimeEpu = 0x0918;    ///< 8 bytes, local time
inline constexpr uint16_t kDcSystemTimeOffset = 0x0920;  ///< 8 bytes
inline constexpr uint16_t kDcSystemTimeDelay = 0x0928;   ///< 4 bytes
// Process data RAM.
inline constexpr uint16_t kProcessRam = 0x1000;

// DL status (0x0110) bits.
inline constexpr uint16_t kDlPdiOperational = 0x0001;
/// Physical link on port p (bits 4..7).
constexpr uint16_t dl_link(int port) { return static_cast<uint16_t>(0x0010u << port); }
/// Loop closed on port p (bits 8, 10, 12, 14): 0 = open (frames go out of the port).
constexpr uint16_t dl_loop_closed(int port) { return static_cast<uint16_t>(0x0100u << (2 * port)); }
/// Communication established on port p (bits 9, 11, 13, 15).
constexpr uint16_t dl_communication(int port) {
  return static_cast<uint16_t>(0x0200u << (2 * port));
}
/// Ports a frame goes through: loop open and communication established (the open-port mask
/// the discovery service reads).
uint8_t open_ports(uint16_t dl_status);
/// Ports with a physical link, whether or not frames pass: the `topology` count masters report.
uint8_t linked_ports(uint16_t dl_status);

// EEPROM control/status (0x0502) bits.
inline constexpr uint16_t kEepromWriteEnable = 0x0001;
inline constexpr uint16_t kEeprom8ByteRead = 0x0040;     ///< the ESC reads 8 bytes (else 4)
inline constexpr uint16_t kEepromCommandRead = 0x0100;   ///< bits 8..10 = 001
inline constexpr uint16_t kEepromCommandWrite = 0x0200;
inline constexpr uint16_t kEepromCommandReload = 0x0400;
inline constexpr uint16_t kEepromCommandMask = 0x0700;
inline constexpr uint16_t kEepromChecksumError = 0x0800;
inline constexpr uint16_t kEepromLoadError = 0x1000;
inline constexpr uint16_t kEepromAcknowledgeError = 0x2000;  ///< missing acknowledge / bad command
inline constexpr uint16_t kEepromWriteError = 0x4000;
inline constexpr uint16_t kEepromBusy = 0x8000;
inline constexpr uint16_t kEepromErrorMask = 0x7800;

/// Application-layer states (AL control/status bits 0..3).
enum class AlState : uint8_t { kInit = 1, kPreOp = 2, kBoot = 3, kSafeOp = 4, kOp = 8 };
inline constexpr uint16_t kAlStateMask = 0x000F;
inline constexpr uint16_t kAlErrorBit = 0x0010;  ///< status: error indication; control: acknowledge

/// "INIT", "PRE-OP", "BOOT", "SAFE-OP", "OP"; "state 0x5" for a value that is none.
std::string to_string(AlState state);
std::optional<AlState> al_state_from(uint16_t value);

/// The ETG.1000.6 name of an AL status code: 0x0011 "invalid requested state change", 0x001B
/// "sync manager watchdog", ...; "unknown AL status code 0x1234" for others.
std::string al_status_code_name(uint16_t code);

// SII EEPROM (ETG.2010), word addresses.
inline constexpr uint16_t kSiiVendorId = 0x0008;     ///< 2 words
inline constexpr uint16_t kSiiProductCode = 0x000A;  ///< 2 words
inline constexpr uint16_t kSiiRevision = 0x000C;     ///< 2 words
inline constexpr uint16_t kSiiSerial = 0x000E;       ///< 2 words
inline constexpr uint16_t kSiiFirstCategory = 0x0040;
inline constexpr uint16_t kSiiCategoryEnd = 0xFFFF;

}  // namespace concert::ethercat::esc
