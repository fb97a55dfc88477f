// The fuzzing build's (-DCONCERT_FUZZ=ON) hooks: libFuzzer's start-up hook answers
// `--write-seeds DIR` before libFuzzer reads its own arguments; LeakSanitizer's suppressions.
#include <cstdlib>

#include "fuzz.hpp"

// urdfdom 3.0 (Debian 12) leaks the links of a URDF whose joints form a loop (e.g. a joint whose
// parent and child are the same link): its links hold their children by shared_ptr, so the loop
// keeps itself alive after the parser gives up. A bug of the library, not of the code under test
// (tests/fuzz/README.md).
extern "C" const char* __lsan_default_suppressions() { return "leak:liburdfdom_model.so\n"; }

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  if (concert::fuzz::handle_write_seeds(*argc, *argv)) std::exit(0);
  return 0;
}
