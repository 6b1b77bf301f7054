// libFuzzer target: scenario text (YAML or JSON) through parse_scenario (scenario.h: yaml-cpp, then
// ctsurg's field-by-field checks). Paths are resolved against a folder that does not exist.
#include "ctsurg/sim/scenario/scenario.h"
#include "fuzz_input_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  ctsurg::fuzz::expect_refusal_or_success(
      [&] { (void)ctsurg::sim::parse_scenario(text, "fuzz.yaml", "/nonexistent-ctsurg-fuzz"); });
  return 0;
}
