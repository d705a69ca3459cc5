// keys and materials: the job file's keys and the materials library, as the CLI lists them.
#include "common.hpp"
#include "trochomill/job.hpp"
#include "trochomill/report/job.hpp"

namespace trochomill::python {

void bind_tool(py::module_& m) {
  m.def(
      "keys", [] { return from_json(job_keys_json()); },
      R"(Every key of the job file, as `trochomill keys --json`: a list of dicts with section,
key, type, unit, allowed (range or choices), default and doc.)");

  m.def(
      "materials", [] { return from_json(materials_json(material_library())); },
      R"(The materials library (force model coefficients with their sources), as `trochomill
materials --json`: a list of dicts; a job names one with [material] name.)");
}

}  // namespace trochomill::python
