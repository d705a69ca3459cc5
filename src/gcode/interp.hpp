// The RS274/NGC interpreter (private to src/gcode): its state as one struct, InterpState, and
// the class that runs a program line by line, Interpreter. Its parts are in files by concern
// as LinuxCNC splits its own (interp_read, interp_convert, interp_cycles, interp_o_word, ...):
//  - interp.cpp: the driver: lines, messages, a line and its block in LinuxCNC's order;
//  - interp_expr.cpp: values: numbers, parameters, [expressions], functions;
//  - interp_block.cpp: blocks: their words, their codes' modal groups, the checks; M70-M73;
//  - interp_coords.cpp: coordinate systems and offsets: G54-G59.3, G10, G92, G52, G28/G30;
//  - interp_tools.cpp: the tool table and tool length offsets (G43, G43.1, G49);
//  - interp_motion.cpp: motion: end points, feeds, lines, arcs and splines into the path and the
//    trace;
//  - interp_cutcomp.cpp: cutter radius compensation (G41/G42, G41.1/G42.1, G40) and its queue;
//  - interp_cycles.cpp: canned cycles (G73 G74 G76 G81-G89) and threading (G33, G33.1, G76);
//  - interp_macro.cpp: Fanuc Macro B (GOTO, IF, WHILE, G65) and subprograms (M98/M99);
//  - interp_oword.cpp: O-words: subroutines, calls, if, loops.
// interp_types.hpp has the data types they share.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

#include "interp_types.hpp"
#include "ngc_lexer.hpp"
#include "trochomill/gcode.hpp"

namespace trochomill::gcode_detail {

// Hidden visibility, as the anonymous namespace of one file was: GCC does not inline a function
// another shared object could replace (-fPIC, which the Python module asks for), and these run
// a few times a block.
#pragma GCC visibility push(hidden)

// Everything the interpreter knows between lines, in one place (LinuxCNC's setup): what it
// reads and where, the parameters and the subroutine frames, the modal state, the coordinate
// systems and the tool, the canned cycles' retained words, the position and the program made.
// Lengths are mm. Cutter compensation keeps its own queue (CutterComp).
struct InterpState {
  explicit InterpState(const GcodeReadOptions& opt) : opt_(opt) {}

  // The options and the dialect (set first: the members below read them).
  GcodeReadOptions opt_;
  bool haas_ = opt_.dialect == Dialect::haas;
  bool mach3_ = opt_.dialect == Dialect::mach3;
  bool fanuc_ = opt_.dialect == Dialect::fanuc || haas_;  // Fanuc with Macro B (Haas too)
  // O<n> lines start programs, not O-word statements (Fanuc, Haas, Mach3); G15/G16 polar.
  bool o_numbers_ = fanuc_ || mach3_;
  // M98 P<n> L<times> calls program O<n>, M99 returns: those and LinuxCNC 2.9's Fanuc-style
  // subroutines (a bare O<n> line in its O-word language).
  bool m98_ = o_numbers_ || opt_.dialect == Dialect::linuxcnc;
  bool polar_mode_ = false;  // G16 .. G15
  bool decimal_warned_ = false;
  // This block's subprogram call and return (Fanuc).
  std::optional<std::pair<double, double>> pending_m98_;  // P, L of this block's M98
  bool pending_m97_ = false;  // the call is Haas's M97: P is a block number of this program
  bool pending_m99_ = false;
  double m99_p_ = -1;
  // The text: the program and the subroutine files, where the next line is, the line and the
  // block being run.
  std::deque<Source> sources_;
  Cursor cur_;
  std::size_t line_offset_ = 0;  // of the line being run
  std::size_t main_lines_ = 0;
  ngc::Line line_;
  Block block_;
  int depth_ = 0;  // nesting of read_value
  char word_ = 0;  // the word whose value is being read (for messages)
  std::size_t word_at_ = 0;
  // Parameters, subroutine calls, saved modal state (M70-M73), a subroutine's returned value.
  std::vector<double> params_;
  std::unordered_map<std::string, double> globals_;
  std::vector<Frame> frames_;
  ModalSave saved_;
  std::vector<ModalSave> sub_saved_;
  double value_ = 0;
  bool value_returned_ = false;

  // Modal state (lengths in mm).
  int motion_ = -1;  // 0, 10, 20, 30, 730, 810 .. 890; -1 = none / G80
  Plane plane_ = Plane::xy;
  double unit_ = 1.0;
  bool absolute_ = true, arc_absolute_ = false;
  FeedMode feed_mode_ = FeedMode::per_minute;
  double feed_ = 0;  // mm/min (G95: mm/rev)
  // Feed words and modal restores that set feed_, counted; the count and feed_ as the block
  // being run started; whether the move being made is a plain G0..G3 of the block's words.
  std::uint64_t feed_events_ = 0, block_feed_events_ = 0;
  double block_feed_before_ = 0;
  bool plain_move_ = false;
  bool feed_given_ = false;
  double inverse_f_ = -1;  // G93: this block's F
  double speed_ = 0;
  bool css_ = false;        // G96 .. G97
  double css_max_rpm_ = 0;  // G96's D (0: none)
  bool css_warned_ = false, tcp_warned_ = false;
  bool spindle_on_ = false;
  int spindle_dir_ = 0;  // 1 clockwise (M3), -1 counterclockwise (M4), 0 stopped
  // G99 (retract to R) until G98: LinuxCNC's interpreter starts so (its setup leaves the mode
  // at its first value, R_PLANE); Fanuc starts in G98.
  bool retract_r_ = !fanuc_;
  double tool_loaded_ = 0, tool_selected_ = 0;
  double tool_z_ = 0;  // active tool length offset (mm)
  std::map<int, ToolTableEntry> tools_ = opt_.tools;
  // Coordinate systems.
  int system_ = 1;
  Vec3 origin_ = Vec3::Zero();
  double rotation_ = 0;
  Vec3 g92_ = Vec3::Zero();
  Vec3 out_origin_ = Vec3::Zero();
  double out_rotation_ = 0;
  bool g28_given_ = false, g30_given_ = false, home_warned_ = false, tool_warned_ = false;
  double unknown_tool_ = -1;  // the H of an active G43 whose tool the table lacks
  // G54 .. G59.3 (1 .. 9), then the extra systems P1 .. kExtraSystems (10 ..): Fanuc's G54.1 P,
  // Haas's G154 P (G110 .. G129 its first 20), Mach3's G59 P7 .. (its fixtures 7 ..).
  std::vector<bool> system_warned_ = std::vector<bool>(10 + kExtraSystems, false);
  // Fanuc's external work offset (G10 L2 P0): added to every system's origin (mm).
  Vec3 ext_offset_ = Vec3::Zero();
  // Fanuc's and Haas's offset registers (G10 L10 .. L13): H length and D radius (or Haas's
  // diameter), geometry and wear (mm); a register G10 never set reads the tool table.
  struct OffsetRegister {
    std::optional<double> h_geometry, h_wear, d_geometry, d_wear;
  };
  std::map<int, OffsetRegister> registers_;
  // Canned cycles.
  int cycle_motion_ = -1;
  double cycle_r_ = 0, cycle_z_ = 0, cycle_q_ = 0, cycle_p_ = 0, cycle_il_ = 0;
  std::array<double, 3> cycle_ijk_{};  // G87's I J K (mm)
  bool g88_warned_ = false, shift_warned_ = false;
  bool cycle_il_flag_ = false;
  // The axes besides X Y Z (A B C degrees, U V W mm): program coordinates, G92's offsets, the
  // output frame's value at the path's end and the output system's origin; where the block's
  // move takes them (set by ends(), used by the move it emits); whether a word of them was read.
  ExtraAxes xpos_{}, xg92_{}, xout_{}, xout_origin_{}, xnext_{};
  bool extra_seen_ = false;
  // Splines: G5's first control point offset when its I J are left out (the last G5's -P -Q,
  // mm), G5.2's control points (program mm) with their weights and the order (LinuxCNC 2.9).
  double spline_i_ = 0, spline_j_ = 0;
  std::vector<Vec3> nurbs_points_;
  std::vector<double> nurbs_weights_;
  int nurbs_order_ = 3;
  // Fanuc's G51 scaling (about its centre, per axis; negative: a mirror) and G68 rotation
  // (about its centre in XY, degrees), applied to program coordinates in that order before
  // the work offset.
  bool scale_on_ = false, rotate_on_ = false;
  Vec3 scale_centre_ = Vec3::Zero(), scale_k_ = Vec3::Ones();
  double rot_cx_ = 0, rot_cy_ = 0, rot_deg_ = 0;
  // Position.
  Vec3 cur_pos_ = Vec3::Zero();  // program coordinates (mm)
  Vec3 out_pos_ = Vec3::Zero();  // output frame, the path's end
  bool started_ = false;
  bool ended_ = false;
  GcodeProgram prog_;
};

class Interpreter;

// Cutter radius compensation (G41/G42, G41.1/G42.1, G40) as LinuxCNC runs it
// (interp_cutcomp.cpp): its own state and the queue of moves that wait for their corner. It
// reads the interpreter's block and modal state and emits its moves through the interpreter.
class CutterComp {
 public:
  explicit CutterComp(Interpreter& interp) : interp_(interp) {}

  [[nodiscard]] bool on() const { return side_ != Side::off; }
  [[nodiscard]] bool on_left() const { return side_ == Side::left; }
  [[nodiscard]] bool moves() const { return on() && radius_ > 0; }
  // The position LinuxCNC reports as #<_x> #<_y> #<_z>: the tool centre while compensation
  // runs (Fanuc's #5041-#5043 too).
  [[nodiscard]] const Vec3& current() const;
  void refuse(std::uint32_t column, const std::string& what) const;
  void start(int g, std::uint32_t column);
  void stop();
  void flush_at_stop(std::uint32_t column);
  // Off without a move, as the program ends (M2, M30).
  void turn_off() {
    side_ = Side::off;
    first_ = true;
  }
  void line(const Vec3& p, bool rapid, std::uint32_t column);
  void arc(const Vec3& p, std::uint32_t column);
  void dequeue();
  // The move right after G40 must be straight (the tool is not at the programmed point).
  [[nodiscard]] bool arc_not_allowed() const { return arc_not_allowed_; }
  void allow_arcs() { arc_not_allowed_ = false; }

 private:
  enum class Side { off, left, right };

  struct QueuedMove {
    GcodeMove::Kind kind = GcodeMove::Kind::feed;
    Vec3 end = Vec3::Zero();    // program mm
    double d1 = 0, d2 = 0;      // lines: the direction the end may not turn against
    double c1 = 0, c2 = 0;      // arcs: the centre
    int turn = 0;               // arcs: turns, positive counterclockwise (LinuxCNC's)
    double original_sweep = 0;  // arcs: the sweep as queued (rad); 0: never checked
    double feed = 0;            // mm/min
    std::size_t source = 0, line = 0;
    std::uint32_t column = 0;
  };

  static constexpr double kConcaveTol = 0.05;  // rad, LinuxCNC's TOLERANCE_CONCAVE_CORNER

  [[nodiscard]] bool left() const { return side_ == Side::left; }
  // The tool is inside an arc of this turning sense: left of a counterclockwise one.
  [[nodiscard]] bool inside(int turn) const { return left() ? turn > 0 : turn < 0; }
  static double find_turn(double x1, double y1, double cx, double cy, int turn, double x2,
                          double y2);
  void enqueue(QueuedMove q, std::uint32_t column);
  void set_endpoint(double x, double y);
  void move_endpoint_and_flush(double x, double y, std::uint32_t column);
  [[noreturn]] void gouge(std::uint32_t column, const char* what) const;
  [[noreturn]] void concave_after_stop(std::uint32_t column) const;

  Interpreter& interp_;
  Side side_ = Side::off;
  double radius_ = 0;  // mm
  bool first_ = true;  // the next move starts compensation
  bool arc_not_allowed_ = false;
  bool fanuc_warned_ = false;
  Vec3 centre_ = Vec3::Zero();   // the tool centre (program mm)
  Vec3 emitted_ = Vec3::Zero();  // where the last compensated move to run ends (program mm)
  std::vector<QueuedMove> queue_;
  std::array<double, 2> endpoint_{};  // where the last queued XY move starts
  bool endpoint_valid_ = false;
};

// The interpreter: one program read line by line into a GcodeProgram. Its parts, by concern,
// are in the files named below. The functions declared inline here without a body are defined
// in their section's file and called only from it: GCC then inlines them into their callers, as
// it did when the interpreter was one file (the blocks of a loop ran 5-10 % slower without).
class Interpreter : private InterpState {
 public:
  Interpreter(std::string_view text, std::string_view name, const GcodeReadOptions& opt);
  GcodeProgram run();

 private:
  // ---- interp.cpp: the driver: lines, messages, a line and its block in LinuxCNC's order
  inline bool next_line(std::string_view& raw);
  [[noreturn]] void fail_at(std::uint32_t column, const std::string& what) const;
  // The column of text index i of the current line.
  [[nodiscard]] std::uint32_t col_of(std::size_t i) const {
    return line_.column[std::min(i, line_.column.size() - 1)];
  }
  [[noreturn]] void fail(std::size_t i, const std::string& what) const { fail_at(col_of(i), what); }
  void warn(const std::string& what);
  void count_block();
  inline void run_line(std::string_view raw);
  void execute();
  void polar_words(const BlockCodes& codes);
  inline void set_feed_speed_tool(int feed_mode);
  inline void run_m_codes(bool& stop, bool& pause);
  void check_m_codes() const;
  void check_m66(std::uint32_t column) const;
  inline void set_modes(const BlockCodes& codes);
  inline void run_motion(const BlockCodes& codes);
  void end_program() { ended_ = true; }

  // ---- interp_expr.cpp: values: numbers, parameters, [expressions], functions
  inline double read_number(std::size_t& i);
  inline double checked(double v, std::size_t at) const;
  double read_value(std::size_t& i);
  double read_expression(std::size_t& i);
  enum class Op { none, pow, mul, div, mod, add, sub, eq, ne, gt, ge, lt, le, and_, or_, xor_ };
  inline int precedence(Op op) const;
  inline Op peek_op(std::size_t i, std::size_t& len) const;
  double read_binary(std::size_t& i, int min_prec);
  inline double apply(Op op, double a, double b, std::size_t at) const;
  [[nodiscard]] static double zero_if_vacant(double v) { return std::isnan(v) ? 0.0 : v; }
  bool function_follows(std::size_t i) const;
  double read_function(std::size_t& i);
  double read_parameter(std::size_t& i);
  double fanuc_modal(int index) const;
  double fanuc_variable(int index) const;
  int parameter_index(double v, std::size_t at) const;
  std::string read_name(std::size_t& i);
  double* find_named(const std::string& name);
  double named_value(const std::string& name, std::size_t at);
  std::optional<double> predefined(const std::string& name) const;
  void set_named(const std::string& name, double v, std::uint32_t column);

  // ---- interp_block.cpp: blocks: their words, their codes' modal groups, the checks; M70-M73
  void read_block(std::size_t i);
  static char upper(char c) { return static_cast<char>(c - 'a' + 'A'); }
  void set_numbered();
  void check_fanuc_write(int index, std::size_t at, double v) const;
  // A length word in mm.
  double len(char c) const { return block_[c] * unit_; }
  void polar_end(double& x, double& y) const;
  bool full_circle_ = false;  // this block's G2/G3 is a full circle without an end point
  bool probe_warned_ = false;
  void probe(const Vec3& target, std::uint32_t column);
  void check_range(char c) const;
  void check_words() const;
  BlockCodes group_codes() const;
  void check_unused(int group0, int dwell, int tool_length, bool comp_word) const;
  [[noreturn]] void unsupported_g(int g, std::uint32_t column) const;
  ModalSave& push_sub_saved() {
    sub_saved_.emplace_back();
    return sub_saved_.back();
  }
  void save_modal(ModalSave& m) const;
  void restore_modal(const ModalSave& m);

  // ---- interp_coords.cpp: coordinate systems and offsets: G54-G59.3, G10, G92, G52, G28/G30
  // Parameters of a coordinate system n (1 = G54 .. 9 = G59.3): X at 5201 + 20 n, R at 5210 +
  // 20 n. G92: 5211-5213, enabled at 5210. G28: 5161-5163, G30: 5181-5183. All mm.
  // The extra systems (n >= 10, P = n - 9) at Fanuc's #7001 + 20 (P - 1).
  static std::size_t sys_param(int n, int axis) {
    return static_cast<std::size_t>(n <= 9 ? 5201 + 20 * n + axis : 7001 + 20 * (n - 10) + axis);
  }
  [[nodiscard]] std::string system_name(int n) const;
  void select_system_n(int n);
  void init_offsets();
  void load_system();
  [[nodiscard]] Vec3 to_machine_tip(const Vec3& p) const;
  [[nodiscard]] Vec3 from_machine_tip(const Vec3& m) const;
  [[nodiscard]] Vec3 to_out(const Vec3& p) const;
  [[nodiscard]] Vec3 dir_to_out(const Vec3& d) const;
  void note_system_used(int n);
  void select_system(int g, std::uint32_t column);
  void non_modal(int g, std::uint32_t column);
  void fanuc_g10(std::uint32_t column);
  void g10(std::uint32_t column);
  // A system set by G10 is known: no warning when it is selected later.
  void note_given(int n) { system_warned_[static_cast<std::size_t>(n - 1)] = true; }
  void home_move(int g, std::uint32_t column);
  // Fanuc's G51/G50 and G68/G69: the program's coordinates scaled and turned (to_transformed,
  // from_transformed: points; a direction through to_transformed_dir).
  void program_transform(int g, std::uint32_t column);
  [[nodiscard]] Vec3 to_transformed(Vec3 p) const;
  [[nodiscard]] Vec3 from_transformed(Vec3 p) const;
  [[nodiscard]] Vec3 to_transformed_dir(Vec3 d) const;
  [[nodiscard]] bool transformed() const { return scale_on_ || rotate_on_; }
  // The axes besides X Y Z: a value of axis k (0 = A .. 5 = W) in machine coordinates, back,
  // in the output frame; a word of the block in mm (U V W) or degrees (A B C).
  [[nodiscard]] double xmachine(int k, double p) const {
    return p + xg92_[static_cast<std::size_t>(k)] + params_[sys_param(system_, 3 + k)];
  }
  [[nodiscard]] double xfrom_machine(int k, double m) const {
    return m - params_[sys_param(system_, 3 + k)] - xg92_[static_cast<std::size_t>(k)];
  }
  [[nodiscard]] double xlen(int k) const {
    const char c = kExtraAxes[static_cast<std::size_t>(k)];
    return k >= 3 ? len(c) : block_[c];
  }
  void note_extra_axes();

  // ---- interp_tools.cpp: the tool table and tool length offsets (G43, G43.1, G49)
  void tool_length_offset(int g);
  void note_tool_length(const char* what);

  // ---- interp_motion.cpp: motion: end points, feeds, lines, arcs and splines into the path
  Vec3 ends(bool g53);
  ExtraAxes extras_out(GcodeMove& mv);
  double extra_time_s(const ExtraAxes& out_end, std::uint32_t column);
  void move(bool g53, std::uint32_t column);
  double feed_for(double length_mm, std::uint32_t column);
  // The spindle speed a move runs at (rpm): S, or under G96 (constant surface speed) S m/min
  // (G20: ft/min) over the circumference at the current X, at most D.
  double spindle_rpm(std::uint32_t column);
  void note_feed(double f);
  void check_target(const Vec3& out, std::uint32_t column) const;
  void emit_line(const Vec3& target, bool rapid, std::uint32_t column, bool starts = false);
  void put_line(const Vec3& end, bool rapid, double f, std::uint32_t column, std::size_t source,
                std::size_t line, bool xy);
  [[nodiscard]] const char* unit_name() const { return unit_ == 1.0 ? "mm" : "in"; }
  int plane_code() const { return plane_ == Plane::xy ? 17 : plane_ == Plane::zx ? 18 : 19; }
  void trace(const GcodeMove& mv) const {
    if (opt_.trace) opt_.trace(mv);
  }
  std::size_t append(Segment seg, std::uint32_t column, std::size_t source, std::size_t line);
  void describe(GcodeMove& mv, std::size_t source, std::size_t line) const;
  ArcData arc_data(const Vec3& from, const Vec3& target, std::uint32_t column) const;
  void arc(const Vec3& target, std::uint32_t column);
  // Splines (G5 cubic, G5.1 quadratic, G5.2/G5.3 NURBS): their exact curve as biarcs.
  void spline(std::uint32_t column);
  void nurbs_point(bool fresh, std::uint32_t column);
  void nurbs_end(std::uint32_t column);
  void put_curve(const std::vector<Vec3>& points, const std::vector<double>& weights, int order,
                 std::uint32_t column);
  void put_arc(const Vec3& from, const ArcData& d, double axial, double f, std::uint32_t column,
               std::size_t source, std::size_t line, bool xy, const Vec3* exact_end = nullptr);

  // ---- interp_cycles.cpp: canned cycles (G73 G74 G76 G81-G89) and threading
  void canned_cycle(int g, std::uint32_t column);
  [[nodiscard]] ArcData plane_axes() const;
  void note_fanuc_shift(const std::string& name);
  void line_to(const Vec3& target, bool rapid, std::uint32_t column);
  // Threading (G33, G33.1, LinuxCNC's G76): moves at the pitch times the spindle speed.
  void thread(std::uint32_t column);
  void threading_cycle(std::uint32_t column);

  // ---- interp_macro.cpp: Fanuc Macro B (GOTO, IF, WHILE, G65) and subprograms (M98/M99)
  bool fanuc_statement(std::size_t i);
  void fanuc_end(std::size_t i) const;
  std::string loop_id(std::size_t& i);
  void skip_past_end(const std::string& label, std::size_t at);
  void goto_label(double n, std::size_t at, const char* what = "GOTO");
  void macro_call(std::uint32_t column);
  void subprogram_call();
  void enter(Frame f);
  void subprogram_return();
  static void index_programs(Source& src);
  Frame program_frame(double n, std::uint32_t column);

  // ---- interp_oword.cpp: O-words: subroutines, calls, if, loops
  bool o_statement(std::size_t i);
  void run_after_program_number();
  std::optional<double> o_value(std::size_t& i);
  double o_required(std::size_t& i, std::string_view what);
  void o_end(std::size_t i);
  void index(Source& src);
  std::size_t this_oline();
  std::size_t find_forward(std::size_t from, const std::string& label,
                           std::initializer_list<OKind> kinds, std::string_view what,
                           std::size_t at);
  static std::string show_label(const std::string& label);
  void jump(std::size_t k, bool after);
  Control& open_control(OKind kind, const std::string& label, const Cursor& start);
  Control& open_of(OKind kind, const std::string& label, std::string_view what,
                   std::string_view opener, std::size_t at);
  Control* find_control(const std::string& label);
  void pop_to(const std::string& label);
  void o_word(OKind kind, const std::string& label, std::size_t i, std::size_t at);
  void end_repeat_pass(Control& ctl, const std::string& label);
  void call(const std::string& label, std::size_t i, std::size_t at);
  void return_from_sub();
  std::pair<std::size_t, std::size_t> find_sub(const std::string& label, std::size_t at);

  // Cutter radius compensation: its queue and state; it reads the block and the modal state
  // and emits its moves through the interpreter.
  CutterComp comp_{*this};
  friend class CutterComp;
};

// The interpreter's entry point (read_gcode, reader.cpp).
GcodeProgram interpret_gcode(std::string_view text, std::string_view source_name,
                             const GcodeReadOptions& options);

#pragma GCC visibility pop

}  // namespace trochomill::gcode_detail
