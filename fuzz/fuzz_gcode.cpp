// The G-code interpreter: every input is a path or an InputError naming file:line:column.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    // Bounded work per input (a loop without end stops at the block budget) and no files: the
    // program's folder does not exist, so o<name> call finds no subroutine file.
    GcodeReadOptions options;
    // Every dialect's reader, chosen by the first byte (a seed's text picks one as it starts).
    constexpr Dialect kDialects[] = {Dialect::linuxcnc, Dialect::fanuc, Dialect::sinumerik,
                                     Dialect::grbl,     Dialect::haas,  Dialect::mach3};
    if (size > 0) options.dialect = kDialects[data[0] % 6];
    options.max_blocks = 2'000;
    options.max_call_depth = 32;
    const GcodeProgram prog = read_gcode(text, "/nonexistent/fuzz.ngc", options);
    (void)prog.path.length_mm();
    (void)gcode_header_keys(text);
  } catch (const InputError&) {
  }
  return 0;
}
