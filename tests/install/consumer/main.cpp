// Plans a job with the installed library and prints what `trochomill plan` prints of it.
#include <cstdio>

#include "trochomill/error.hpp"
#include "trochomill/job.hpp"
#include "trochomill/path.hpp"

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  try {
    const trochomill::Job job = trochomill::load_job(argv[1]);
    const trochomill::PlannedPath p = trochomill::plan_path(job);
    std::printf("%d cycles, path %.3f mm\n", p.info.cycles, p.path.length_mm());
    return 0;
  } catch (const trochomill::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
