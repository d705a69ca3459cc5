// Formatting of results (JSON, CSV, tables, the HTML report): every report header. A command
// or binding may include only the domain it formats (trochomill/report/<domain>.hpp).
#pragma once

#include "trochomill/report/analysis.hpp"
#include "trochomill/report/drawing.hpp"
#include "trochomill/report/force.hpp"
#include "trochomill/report/html.hpp"
#include "trochomill/report/job.hpp"
#include "trochomill/report/mechanism.hpp"
#include "trochomill/report/path.hpp"
#include "trochomill/report/signal.hpp"
#include "trochomill/report/sim.hpp"
#include "trochomill/report/texture.hpp"
