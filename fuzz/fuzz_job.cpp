// The job parser with overrides: the input is a TOML document, then optionally a line
// "#--set" followed by one `key=value` override per line. Every input either builds a job
// or throws InputError; anything else (a crash, a sanitizer report, another exception) is a
// finding.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "trochomill/error.hpp"
#include "trochomill/job.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace trochomill;
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  const std::size_t cut = all.find("\n#--set\n");
  const std::string_view toml = all.substr(0, cut);
  std::vector<Override> overrides;
  try {
    if (cut != std::string_view::npos) {
      std::string_view rest = all.substr(cut + 8);
      while (!rest.empty()) {
        const std::size_t eol = rest.find('\n');
        const std::string_view line = rest.substr(0, eol);
        if (!line.empty()) overrides.push_back(parse_override(std::string(line)));
        if (eol == std::string_view::npos) break;
        rest.remove_prefix(eol + 1);
      }
    }
    const JobDocument doc = JobDocument::parse(toml, "fuzz.toml");
    (void)doc.build(overrides);
  } catch (const InputError&) {
  }
  return 0;
}
