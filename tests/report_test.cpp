// Report helpers: --vary parsing and study tables; the HTML report's decimation and data.
#include "trochomill/report.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/pocket.hpp"

namespace trochomill {
namespace {

// Every run of samples that one pixel column covers keeps its first and last sample and
// the smallest and largest of every series (checked against the runs recomputed here).
// figure_text rounds as the report's page does (web/src/report.js fmtNum(v, 4): toPrecision,
// String(Number(...)), toExponential from 1e6 up and below 1e-4). Expected texts are node's
// own output for these values (ties such as 12345 and 9999.5 round up in magnitude there).
TEST(Report, FigureTextRoundsAsThePage) {
  const std::vector<std::pair<double, std::string>> cases = {{64.956, "64.96"},
                                                             {2216.2, "2216"},
                                                             {0.075, "0.075"},
                                                             {12345, "12350"},
                                                             {180.86, "180.9"},
                                                             {1234567, "1.235e+6"},
                                                             {0.00001234, "1.234e-5"},
                                                             {-3.14159, "-3.142"},
                                                             {100000, "100000"},
                                                             {0.0001, "0.0001"},
                                                             {999.95, "1000"},
                                                             {0.125, "0.125"},
                                                             {9999.5, "10000"},
                                                             {2.5, "2.5"},
                                                             {1e-4 * 1.00005, "0.0001"},
                                                             {395.3380732915399, "395.3"},
                                                             {0.07500000001, "0.075"},
                                                             {123456, "123500"},
                                                             {5e-324, "4.941e-324"},
                                                             {1.7976931348623157e308, "1.798e+308"},
                                                             {0.3, "0.3"},
                                                             {0, "0"}};
  for (const auto& [v, want] : cases) EXPECT_EQ(figure_text(v), want) << v;
  EXPECT_EQ(figure_text(std::nan("")), "-");
  EXPECT_EQ(figure_text(2216.2, 6), "2216.2");
}

TEST(Report, DecimationKeepsEveryExtremeOfEveryColumn) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0, 1);
  const std::size_t n = 100003, columns = 487;
  std::vector<double> a(n), b(n), c(n);
  for (std::size_t i = 0; i < n; ++i) {
    a[i] = std::sin(1e-3 * static_cast<double>(i)) + 0.1 * noise(rng);
    b[i] = noise(rng);
    c[i] = i % 1000 < 300 ? std::numeric_limits<double>::quiet_NaN() : noise(rng);  // gaps
  }
  const auto idx = decimation_indices(n, {&a, &b, &c}, columns);
  ASSERT_TRUE(std::is_sorted(idx.begin(), idx.end()));
  ASSERT_EQ(std::adjacent_find(idx.begin(), idx.end()), idx.end());
  EXPECT_LE(idx.size(), columns * 8);
  EXPECT_GE(idx.size(), columns * 2);
  const auto kept = [&idx](std::size_t i) { return std::binary_search(idx.begin(), idx.end(), i); };
  for (std::size_t k = 0; k < columns; ++k) {
    const std::size_t lo = k * n / columns, hi = (k + 1) * n / columns;
    EXPECT_TRUE(kept(lo) && kept(hi - 1)) << "column " << k;
    for (const std::vector<double>* y : {&a, &b, &c}) {
      double mn = std::numeric_limits<double>::infinity(), mx = -mn;
      for (std::size_t i = lo; i < hi; ++i) {
        if (!std::isnan((*y)[i])) mn = std::min(mn, (*y)[i]), mx = std::max(mx, (*y)[i]);
      }
      if (std::isinf(mn)) continue;  // all NaN here
      bool has_min = false, has_max = false;
      for (const std::size_t i : idx) {
        if (i < lo || i >= hi) continue;
        has_min = has_min || (*y)[i] == mn;
        has_max = has_max || (*y)[i] == mx;
      }
      EXPECT_TRUE(has_min && has_max) << "column " << k;
    }
  }
  // Short series are kept whole.
  const auto all = decimation_indices(2 * columns, {&a}, columns);
  EXPECT_EQ(all.size(), 2 * columns);
}

// The page's data: the summary is analyze's JSON as it is, the path is sampled uniformly,
// and no "</" can end the script element the document sits in.
TEST(Report, DataDocumentHoldsTheAnalysisAndCannotCloseItsScript) {
  ReportData d;
  d.job = load_job(test::example("wagih2023/circular.toml"));
  d.job_file = "circular.toml";
  d.job_text = "# </script><script>alert(1)</script>\n";
  d.command = "trochomill report circular.toml -o r.html";
  d.path = plan_path(d.job).path;
  d.metrics = analyze_process(d.job, d.path);
  const std::string text = report_data_json(d);
  EXPECT_EQ(text.find("</"), std::string::npos);
  const auto doc = nlohmann::json::parse(text);
  EXPECT_EQ(doc["summary"], nlohmann::json::parse(metrics_json(d.job, d.metrics)));
  EXPECT_EQ(doc["job_text"], d.job_text);
  EXPECT_EQ(doc["path"]["samples"], 6001);
  EXPECT_EQ(doc["path"]["x_mm"].size(), 6001u);
  // dt is the path's duration over 6000 to six significant digits.
  EXPECT_NEAR(doc["path"]["dt_s"].get<double>(), d.path.duration_s() / 6000,
              1e-5 * d.path.duration_s() / 6000);
  EXPECT_FALSE(doc.contains("mechanism"));
  EXPECT_FALSE(doc.contains("simulation"));
  const std::string html = report_html(d);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  // Without a simulation the page carries no three.js.
  EXPECT_EQ(html.find("TrochomillView3D="), std::string::npos);
  EXPECT_NE(html.find("trochomill-data"), std::string::npos);
}

// A curved slot's report carries the drawing's other layers (the part under the path): the
// example's part.dxf, written by ezdxf, holds a ring (centre (40, 40), radius 30) and an
// outline (-15..95 x -15..85) besides the centreline. A drawing whose other layer cannot be
// read (three lines meeting: a branch) keeps the report, without them and with a note.
// A pocket's [stock] mesh in the page's data: its plan view at the first level (z = -3 mm on
// the cored blank: the block's outline and the core's, whose radius there is 8 + 2 (4.5 - 3) /
// 4.5 = 8.667 mm about (36, 33), FreeCAD's chords within 0.01 mm of it); none without a mesh.
TEST(Report, APocketsStockMeshIsDrawnAtTheFirstLevel) {
  const auto data = [](const Job& job) {
    ReportData d;
    d.job = job;
    d.path = plan_pocket(d.job).path;
    return nlohmann::json::parse(report_data_json(d))["path"];
  };
  const nlohmann::json p = data(load_job(test::example("pockets/cored.toml")));
  const auto& st = p["stock"];
  ASSERT_FALSE(st.is_null());
  EXPECT_EQ(st["file"], "cored-blank.stl");
  EXPECT_EQ(st["z_mm"].get<double>(), -3.0);
  int breaks = 0, on_core = 0;
  for (std::size_t k = 0; k < st["x_mm"].size(); ++k) {
    if (st["x_mm"][k].is_null()) {
      ++breaks;
      continue;
    }
    const double x = st["x_mm"][k], y = st["y_mm"][k];
    if (breaks == 0) {
      EXPECT_TRUE(std::abs(x + 5) < 1e-9 || std::abs(x - 85) < 1e-9 || std::abs(y + 5) < 1e-9 ||
                  std::abs(y - 55) < 1e-9)
          << x << " " << y;
    } else {
      // The core's section: FreeCAD's facets (0.01 mm deflection) and the page's six digits.
      EXPECT_NEAR(std::hypot(x - 36, y - 33), 8 + 2 * 1.5 / 4.5, 0.02) << x << " " << y;
      ++on_core;
    }
  }
  EXPECT_EQ(breaks, 1);
  EXPECT_GT(on_core, 20);
  EXPECT_TRUE(data(load_job(test::example("pockets/plate.toml")))["stock"].is_null());
}

TEST(Report, ACurvedSlotShowsTheDrawingsOtherLayers) {
  const auto data = [](const Job& job) {
    ReportData d;
    d.job = job;
    d.path = plan_slot(d.job).path;
    d.metrics = analyze_process(d.job, d.path);
    return nlohmann::json::parse(report_data_json(d))["path"];
  };
  nlohmann::json p = data(load_job(test::example("curves/bend.toml")));
  const auto& dr = p["drawing"];
  EXPECT_EQ(dr["layers"], nlohmann::json::parse(R"(["RING", "OUTLINE"])"));
  EXPECT_TRUE(dr["note"].is_null());
  ASSERT_EQ(dr["x_mm"].size(), dr["y_mm"].size());
  double x_lo = 1e9, x_hi = -1e9, y_lo = 1e9, y_hi = -1e9;
  int breaks = 0, on_ring = 0;
  for (std::size_t k = 0; k < dr["x_mm"].size(); ++k) {
    if (dr["x_mm"][k].is_null()) {
      ++breaks;
      continue;
    }
    const double x = dr["x_mm"][k], y = dr["y_mm"][k];
    x_lo = std::min(x_lo, x), x_hi = std::max(x_hi, x);
    y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
    // Six significant digits in the page's data: 1e-4 mm at 95 mm.
    if (breaks == 0) {
      EXPECT_NEAR(std::hypot(x - 40, y - 40), 30.0, 1e-4);
      ++on_ring;
    }
  }
  EXPECT_EQ(breaks, 1);
  // The ring as chords of sagitta <= 0.01 mm: 2 pi / (2 acos(1 - 0.01 / 30)) = 122 or more.
  EXPECT_GE(on_ring, 122);
  EXPECT_NEAR(x_lo, -15, 1e-9);
  EXPECT_NEAR(x_hi, 95, 1e-9);
  EXPECT_NEAR(y_lo, -15, 1e-9);
  EXPECT_NEAR(y_hi, 85, 1e-9);
  // The plot's box holds the drawing.
  EXPECT_LE(p["slot"]["x_min_mm"].get<double>(), -15);
  EXPECT_GE(p["slot"]["y_max_mm"].get<double>(), 85);

  const auto dir = test::scratch_dir("report-drawing");
  std::string dxf = "0\nSECTION\n2\nENTITIES\n";
  const auto line = [&](const char* layer, double x0, double y0, double x1, double y1) {
    dxf += fmt::format("0\nLINE\n8\n{}\n10\n{}\n20\n{}\n11\n{}\n21\n{}\n", layer, x0, y0, x1, y1);
  };
  line("C", 0, 0, 0, 50);
  line("FORK", 30, 0, 40, 0);
  line("FORK", 30, 0, 30, 10);
  line("FORK", 30, 0, 20, 5);
  dxf += "0\nENDSEC\n0\nEOF\n";
  std::ofstream(dir / "fork.dxf") << dxf;
  const Job job = parse_job(
      "[geometry]\nfile = \"fork.dxf\"\n[tool]\ndiameter = 8.0\nteeth = 3\n[slot]\nalong = "
      "\"C\"\nwidth = 12.0\ndepth = 2.0\n[cutting]\nfeed_rate = 900.0\nspindle_speed = 6000.0\n"
      "[path]\ntype = \"circular\"\nstep = 1.0\n",
      (dir / "fork.toml").string());
  p = data(job);
  EXPECT_TRUE(p["drawing"]["x_mm"].empty());
  const std::string note = p["drawing"]["note"].get<std::string>();
  EXPECT_NE(note.find("the drawing's other layers are not shown"), std::string::npos) << note;
  EXPECT_NE(note.find("layer 'FORK': a branch at (30, 0) mm"), std::string::npos) << note;
}

}  // namespace
}  // namespace trochomill
