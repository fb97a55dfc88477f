#pragma once
// Where the tests find their data: the public CONCERT module database and the real scans
// (../shared/data, read in place, never copied: CONCERT_SHARED_DATA) and the project's own files
// (CONCERT_SOURCE_DIR). Both are defined for every test by concert_add_test.

#include <string>

namespace concert::test_data {

/// The public CONCERT module database (esc_index.yaml, module JSON, meshes).
inline const std::string kPublicDb = std::string(CONCERT_SHARED_DATA) + "/concert_resources";
/// The project's module database (data/module_db).
inline const std::string kProjectDb = std::string(CONCERT_SOURCE_DIR) + "/data/module_db";
/// The assembly files shipped with the simulated bus (libs/simbus/examples).
inline const std::string kExamples = std::string(CONCERT_SOURCE_DIR) + "/libs/simbus/examples";
/// Real EtherCAT scans of the CONCERT robot.
inline const std::string kRealScans = std::string(CONCERT_SHARED_DATA) + "/ethercat";

}  // namespace concert::test_data
