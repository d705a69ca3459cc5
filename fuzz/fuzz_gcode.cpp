// The G-code reader: every input is a path or an InputError naming file:line:column.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const GcodeProgram prog = read_gcode(text, "fuzz.ngc");
    (void)prog.path.length_mm();
    (void)gcode_header_keys(text);
  } catch (const InputError&) {
  }
  return 0;
}
