#include "fibre/io/system_io.hpp"

#include <charconv>
#include <climits>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "fibre/algebra/assembly.hpp"

namespace fibre {

namespace {

constexpr const char *kMagic = "fibre_contact_system";
constexpr int kBodyFields = 17;
constexpr int kContactFieldsV1 = 2 + 12 + 1 + kMaxRows;
constexpr int kContactFieldsV2 = kContactFieldsV1 + 3; // + mu, mu_roll, mu_twist
// version 3: + restitution, damping, wall velocity (3) and angular velocity (3)
constexpr int kContactFieldsV3 = kContactFieldsV2 + 8;
// version 4: + the elastic rows (a bit per row 1..5) and their springs (rows 1..5)
// version 5: the same, with bit 5 for an elastic normal row (the material's spring)
constexpr int kContactFieldsV5 = kContactFieldsV3 + kMaxRows;
// version 6: + an obstacle sphere's radius (0 for a flat or region wall)
constexpr int kContactFieldsV6 = kContactFieldsV5 + 1;
// version 7: + the springs' own damping (rows 1..5, -1 for the contact's)
// version 8: the same, with bit 6 of the elastic rows for an implicit normal row
constexpr int kContactFieldsV8 = kContactFieldsV6 + kMaxRows - 1;
// version 9: + the normal row's penetration (Contact::penetration)
constexpr int kContactFieldsV9 = kContactFieldsV8 + 1;
// version 10: + cohesion's pull-off force and gap shift (Contact::pull, gap_shift)
// version 11: the same, with bit 7 of the elastic rows for a split penetration (Contact::split)
constexpr int kContactFields = kContactFieldsV9 + 2;
// Unit vectors must read back as unit vectors; exported data are far more exact than this.
constexpr double kUnitTol = 1e-6;

// ---- writing ----

// %.17g without the locale: std::to_chars with 17 significant digits.
void put_real(std::string &s, double v)
{
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::general, 17);
  s.append(buf, r.ptr);
}

void put_vec(std::string &s, const Vec3 &v)
{
  for (int i = 0; i < 3; ++i) {
    s += ' ';
    put_real(s, v[i]);
  }
}

void check_stream(const std::ostream &out, const std::string &what)
{
  if (!out) throw std::runtime_error("cannot write " + what);
}

// ---- reading ----

// A printable excerpt of a token or line for error messages (inputs may be binary).
std::string excerpt(std::string_view s)
{
  std::string out;
  for (char c : s.substr(0, 40)) out += (c >= 32 && c < 127) ? c : '?';
  if (s.size() > 40) out += "...";
  return out;
}

class Reader {
 public:
  explicit Reader(std::string_view text) : text_(text) {}

  [[noreturn]] void fail(const std::string &msg) const
  {
    throw std::runtime_error("system file, line " + std::to_string(line_no_) + ": " + msg);
  }

  std::size_t remaining() const { return text_.size() - pos_; }

  // The next line that is neither blank nor a comment, split into tokens; false at the end.
  bool next(std::vector<std::string_view> &tokens)
  {
    while (pos_ < text_.size()) {
      std::size_t end = text_.find('\n', pos_);
      if (end == std::string_view::npos) end = text_.size();
      const std::string_view line = text_.substr(pos_, end - pos_);
      pos_ = end < text_.size() ? end + 1 : end;
      ++line_no_;
      split(line, tokens);
      if (!tokens.empty() && tokens[0][0] != '#') return true;
    }
    ++line_no_; // errors at the end point past the last line
    return false;
  }

  // The next line, which must exist: `what` names what was expected.
  void need(std::vector<std::string_view> &tokens, const std::string &what)
  {
    if (!next(tokens)) fail("unexpected end of input, expected " + what);
  }

  // A keyword line "keyword v1 .. vn" with exactly n values.
  void keyword(std::vector<std::string_view> &tokens, const char *word, std::size_t values,
               const char *usage)
  {
    keyword(tokens, word, values, values, usage);
  }
  // A keyword line with between min_values and max_values values.
  void keyword(std::vector<std::string_view> &tokens, const char *word, std::size_t min_values,
               std::size_t max_values, const char *usage)
  {
    need(tokens, std::string("'") + usage + "'");
    if (tokens[0] != word || tokens.size() < min_values + 1 || tokens.size() > max_values + 1)
      fail(std::string("expected '") + usage + "', found '" + excerpt(joined(tokens)) + "'");
  }

  double real(std::string_view tok, const std::string &what) const
  {
    double v = 0;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (r.ec == std::errc::result_out_of_range)
      fail("value '" + excerpt(tok) + "' out of range (" + what + ")");
    if (r.ec != std::errc() || r.ptr != tok.data() + tok.size())
      fail("'" + excerpt(tok) + "' is not a number (" + what + ")");
    if (!std::isfinite(v)) fail("non-finite value '" + excerpt(tok) + "' (" + what + ")");
    return v;
  }

  long long integer(std::string_view tok, const std::string &what) const
  {
    long long v = 0;
    const auto r = std::from_chars(tok.data(), tok.data() + tok.size(), v);
    if (r.ec != std::errc() || r.ptr != tok.data() + tok.size())
      fail("'" + excerpt(tok) + "' is not an integer (" + what + ")");
    return v;
  }

  // A count that the rest of the input can hold, at `min_bytes` per item.
  int count(std::string_view tok, const std::string &what, std::size_t min_bytes) const
  {
    const long long n = integer(tok, what);
    if (n < 0) fail(what + " " + std::to_string(n) + " is negative");
    if (n > INT_MAX / kMaxRows || static_cast<unsigned long long>(n) > remaining() / min_bytes)
      fail(what + " " + std::to_string(n) + " is more than the rest of the input can hold");
    return static_cast<int>(n);
  }

  void fields(const std::vector<std::string_view> &tokens, std::size_t n,
              const std::string &what) const
  {
    if (tokens.size() != n)
      fail(what + ": expected " + std::to_string(n) + " values, found " +
           std::to_string(tokens.size()));
  }

 private:
  static void split(std::string_view line, std::vector<std::string_view> &tokens)
  {
    tokens.clear();
    std::size_t i = 0;
    auto blank = [](char c) {
      return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
    };
    while (i < line.size()) {
      while (i < line.size() && blank(line[i])) ++i;
      const std::size_t start = i;
      while (i < line.size() && !blank(line[i])) ++i;
      if (i > start) tokens.push_back(line.substr(start, i - start));
    }
  }

  static std::string joined(const std::vector<std::string_view> &tokens)
  {
    std::string s;
    for (std::size_t i = 0; i < tokens.size() && s.size() < 60; ++i)
      s += (i ? " " : "") + std::string(tokens[i].substr(0, 60));
    return s;
  }

  std::string_view text_;
  std::size_t pos_ = 0;
  int line_no_ = 0;
};

Vec3 read_vec(const Reader &in, const std::vector<std::string_view> &t, int first,
              const std::string &what)
{
  return Vec3(in.real(t[first], what), in.real(t[first + 1], what), in.real(t[first + 2], what));
}

void check_unit(const Reader &in, const Vec3 &v, const std::string &what)
{
  if (std::abs(v.norm() - 1.0) > kUnitTol) in.fail(what + " is not a unit vector");
}

} // namespace

void write_system(std::ostream &out, const ContactSystem &sys)
{
  std::string s;
  s += std::string(kMagic) + " " + std::to_string(kSystemFormatVersion) + "\n";
  s += "# fibre_contact " FIBRE_VERSION "\n";
  s += "rows " + std::to_string(sys.rows()) + "\n";
  s += "spook ";
  put_real(s, sys.params().h);
  s += ' ';
  put_real(s, sys.params().damping);
  s += ' ';
  put_real(s, sys.params().max_recovery);
  s += ' ';
  put_real(s, sys.params().bounce_speed);
  s += "\nbodies " + std::to_string(sys.num_bodies()) + " " +
       std::to_string(sys.num_owned_bodies()) + "\n";
  out << s;
  for (const Body &b : sys.bodies()) {
    s.clear();
    put_real(s, b.mass);
    s += ' ';
    put_real(s, b.radius);
    for (const Vec3 *v : {&b.x, &b.v, &b.omega, &b.force, &b.torque}) put_vec(s, *v);
    s += '\n';
    out << s;
  }
  out << "contacts " << sys.num_contacts() << "\n";
  for (const Contact &c : sys.contacts()) {
    s = std::to_string(c.a) + " " + std::to_string(c.b);
    for (const Vec3 *v : {&c.normal, &c.t1, &c.t2, &c.point}) put_vec(s, *v);
    s += ' ';
    put_real(s, c.gap);
    for (double eps : c.compliance) {
      s += ' ';
      put_real(s, eps);
    }
    for (double f :
         {c.friction.mu, c.friction.mu_roll, c.friction.mu_twist, c.restitution, c.damping}) {
      s += ' ';
      put_real(s, f);
    }
    for (const Vec3 *v : {&c.wall_v, &c.wall_omega}) put_vec(s, *v);
    int elastic = c.elastic[0] ? 1 << (kMaxRows - 1) : 0;
    if (c.implicit_normal) elastic |= 1 << kMaxRows;
    if (c.split) elastic |= 1 << (kMaxRows + 1);
    for (int r = 1; r < kMaxRows; ++r) elastic |= c.elastic[r] ? 1 << (r - 1) : 0;
    s += ' ' + std::to_string(elastic);
    for (int r = 1; r < kMaxRows; ++r) {
      s += ' ';
      put_real(s, c.spring[r]);
    }
    s += ' ';
    put_real(s, c.wall_radius);
    for (int r = 1; r < kMaxRows; ++r) {
      s += ' ';
      put_real(s, c.spring_damping[r]);
    }
    for (double v : {c.penetration, c.pull, c.gap_shift}) {
      s += ' ';
      put_real(s, v);
    }
    s += '\n';
    out << s;
  }
  out << "mask " << sys.row_mask().size() << "\n";
  for (unsigned char m : sys.row_mask()) out << (m ? "1\n" : "0\n");
  out << "rhs " << sys.rhs().size() << "\n";
  for (Eigen::Index i = 0; i < sys.rhs().size(); ++i) {
    s.clear();
    put_real(s, sys.rhs()[i]);
    s += '\n';
    out << s;
  }
  out << "end\n";
  check_stream(out, "the system");
}

void write_system_file(const std::string &path, const ContactSystem &sys)
{
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot open '" + path + "' for writing");
  write_system(out, sys);
  out.close();
  check_stream(out, "'" + path + "'");
}

namespace {

using Tokens = std::vector<std::string_view>;

// The header line; returns the format version.
long long read_header(Reader &in, Tokens &t)
{
  in.need(t, std::string("the header '") + kMagic + " 1'");
  if (t[0] != kMagic || t.size() != 2)
    in.fail(std::string("not a fibre_contact system file (expected '") + kMagic +
            " <version>', found '" + excerpt(t[0]) + "')");
  const long long version = in.integer(t[1], "format version");
  if (version < 1 || version > kSystemFormatVersion)
    in.fail("unsupported format version " + std::to_string(version) + " (this reader knows 1 to " +
            std::to_string(kSystemFormatVersion) + ")");
  return version;
}

// The contact line's token count in this version.
int contact_fields_of(long long version)
{
  return version == 1   ? kContactFieldsV1
         : version == 2 ? kContactFieldsV2
         : version == 3 ? kContactFieldsV3
         : version <= 5 ? kContactFieldsV5
         : version == 6 ? kContactFieldsV6
         : version <= 8 ? kContactFieldsV8
         : version == 9 ? kContactFieldsV9
                        : kContactFields;
}

SpookParams read_spook(Reader &in, Tokens &t, long long version)
{
  // version 2 may add the bound of the overlap recovery speed (0, unbounded, when absent),
  // version 3 also the bounce speed (0 when absent)
  if (version == 1)
    in.keyword(t, "spook", 2, "spook <h> <damping>");
  else if (version == 2)
    in.keyword(t, "spook", 2, 3, "spook <h> <damping> [max_recovery]");
  else
    in.keyword(t, "spook", 2, 4, "spook <h> <damping> [max_recovery [bounce_speed]]");
  SpookParams params;
  params.h = in.real(t[1], "time step h");
  params.damping = in.real(t[2], "damping");
  if (t.size() >= 4) params.max_recovery = in.real(t[3], "max_recovery");
  if (t.size() >= 5) params.bounce_speed = in.real(t[4], "bounce_speed");
  if (!(params.max_recovery >= 0)) in.fail("max_recovery must be non-negative");
  if (!(params.bounce_speed >= 0)) in.fail("bounce_speed must be non-negative");
  if (!(params.h > 0)) in.fail("time step h must be positive");
  if (!(params.damping >= 0)) in.fail("damping must be non-negative");
  return params;
}

std::vector<Body> read_bodies(Reader &in, Tokens &t, long long &owned)
{
  in.keyword(t, "bodies", 2, "bodies <count> <num_owned>");
  const int nb = in.count(t[1], "body count", 2 * kBodyFields);
  owned = in.integer(t[2], "owned body count");
  if (owned < 0 || owned > nb)
    in.fail("owned body count " + std::to_string(owned) + " is not in [0, " + std::to_string(nb) +
            "]");
  std::vector<Body> bodies(nb);
  for (int i = 0; i < nb; ++i) {
    const std::string what = "body " + std::to_string(i);
    in.need(t, what + " of " + std::to_string(nb));
    in.fields(t, kBodyFields, what);
    Body &b = bodies[i];
    b.mass = in.real(t[0], what + " mass");
    b.radius = in.real(t[1], what + " radius");
    if (!(b.mass > 0)) in.fail(what + ": mass must be positive");
    if (!(b.radius > 0)) in.fail(what + ": radius must be positive");
    b.x = read_vec(in, t, 2, what + " position");
    b.v = read_vec(in, t, 5, what + " velocity");
    b.omega = read_vec(in, t, 8, what + " angular velocity");
    b.force = read_vec(in, t, 11, what + " force");
    b.torque = read_vec(in, t, 14, what + " torque");
  }
  return bodies;
}

// A contact line's bodies, frame, gap and compliances (every version).
void read_contact_frame(Reader &in, const Tokens &t, const std::string &what, int nb, int rows,
                        Contact &k)
{
  const long long a = in.integer(t[0], what + " body a");
  const long long b = in.integer(t[1], what + " body b");
  if (a < 0 || a >= nb)
    in.fail(what + ": body index " + std::to_string(a) + " out of range [0, " + std::to_string(nb) +
            ")");
  if (b < -1 || b >= nb)
    in.fail(what + ": body index " + std::to_string(b) + " out of range [-1, " +
            std::to_string(nb) + ")");
  if (a == b) in.fail(what + ": a body in contact with itself");
  k.a = static_cast<int>(a);
  k.b = static_cast<int>(b);
  k.normal = read_vec(in, t, 2, what + " normal");
  k.t1 = read_vec(in, t, 5, what + " tangent t1");
  k.t2 = read_vec(in, t, 8, what + " tangent t2");
  k.point = read_vec(in, t, 11, what + " point");
  k.gap = in.real(t[14], what + " gap");
  check_unit(in, k.normal, what + " normal");
  check_unit(in, k.t1, what + " tangent t1");
  check_unit(in, k.t2, what + " tangent t2");
  if (std::abs(k.normal.dot(k.t1)) > kUnitTol || std::abs(k.normal.dot(k.t2)) > kUnitTol ||
      std::abs(k.t1.dot(k.t2)) > kUnitTol)
    in.fail(what + ": normal, t1 and t2 are not orthogonal");
  for (int r = 0; r < kMaxRows; ++r) {
    const double eps = in.real(t[15 + r], what + " compliance");
    if (r < rows ? !(eps > 0) : eps < 0)
      in.fail(what + ": compliance of row " + std::to_string(r) +
              (r < rows ? " must be positive" : " must not be negative"));
    k.compliance[r] = eps;
  }
}

// A contact line's coefficients, elastic rows, springs, wall radius, springs' damping and
// penetration, as far as the version has them.
void read_contact_coefficients(Reader &in, const Tokens &t, const std::string &what,
                               long long version, Contact &k)
{
  if (version == 1) return; // no coefficients stored: FrictionParams{}
  double *coeff[3] = {&k.friction.mu, &k.friction.mu_roll, &k.friction.mu_twist};
  const char *name[3] = {" mu", " mu_roll", " mu_twist"};
  for (int i = 0; i < 3; ++i) {
    *coeff[i] = in.real(t[kContactFieldsV1 + i], what + name[i]);
    if (*coeff[i] < 0) in.fail(what + ":" + name[i] + " must not be negative");
  }
  if (version == 2) return;
  k.restitution = in.real(t[kContactFieldsV2], what + " restitution");
  if (!(k.restitution >= 0 && k.restitution <= 1))
    in.fail(what + ": restitution must be in [0, 1]");
  k.damping = in.real(t[kContactFieldsV2 + 1], what + " damping");
  if (!(k.damping >= 0 || k.damping == -1))
    in.fail(what + ": damping must be non-negative, or -1 for the system's");
  k.wall_v = read_vec(in, t, kContactFieldsV2 + 2, what + " wall velocity");
  k.wall_omega = read_vec(in, t, kContactFieldsV2 + 5, what + " wall angular velocity");
  if (!k.is_wall() && (k.wall_v != Vec3::Zero() || k.wall_omega != Vec3::Zero()))
    in.fail(what + ": a pair cannot have a wall velocity");
  if (version == 3) return;
  const long long elastic = in.integer(t[kContactFieldsV3], what + " elastic rows");
  if (version == 4 && (elastic < 0 || elastic >= (1 << (kMaxRows - 1))))
    in.fail(what + ": elastic rows must be a bit mask of rows 1 to 5, in [0, 31]");
  if (version <= 7 && (elastic < 0 || elastic >= (1 << kMaxRows)))
    in.fail(what + ": elastic rows must be a bit mask of rows 1 to 5 and the normal row, in [0, "
                   "63]");
  if (version <= 10 && (elastic < 0 || elastic >= (1 << (kMaxRows + 1))))
    in.fail(what + ": elastic rows must be a bit mask of rows 1 to 5, the normal row and its "
                   "implicit relaxation, in [0, 127]");
  if (elastic < 0 || elastic >= (1 << (kMaxRows + 2)))
    in.fail(what + ": elastic rows must be a bit mask of rows 1 to 5, the normal row, its "
                   "implicit relaxation and a split penetration, in [0, 255]");
  k.elastic[0] = (elastic >> (kMaxRows - 1)) & 1;
  k.implicit_normal = (elastic >> kMaxRows) & 1;
  k.split = (elastic >> (kMaxRows + 1)) & 1;
  if (k.implicit_normal && !k.elastic[0])
    in.fail(what + ": an implicit normal row must be elastic (bit 5)");
  if (k.split && !k.elastic[0])
    in.fail(what + ": a split penetration's row must be elastic (bit 5)");
  for (int r = 1; r < kMaxRows; ++r) {
    k.elastic[r] = (elastic >> (r - 1)) & 1;
    k.spring[r] = in.real(t[kContactFieldsV3 + r], what + " spring");
    if (!k.elastic[r] && k.spring[r] != 0)
      in.fail(what + ": a spring on row " + std::to_string(r) + ", which is not elastic");
  }
  if (version <= 5) return;
  k.wall_radius = in.real(t[kContactFieldsV5], what + " wall radius");
  // version 7 also has concave walls (< 0)
  if (!(k.wall_radius >= 0 || version >= 7) || (!k.is_wall() && k.wall_radius != 0))
    in.fail(what + ": the wall radius must be >= 0 (any value from version 7), and 0 for a pair");
  if (version <= 6) return;
  for (int r = 1; r < kMaxRows; ++r) {
    const double d = in.real(t[kContactFieldsV6 + r - 1], what + " spring damping");
    if (!(d >= 0 || d == -1))
      in.fail(what + ": a spring's damping must be non-negative, or -1 for the contact's");
    k.spring_damping[r] = d;
  }
  if (version <= 8) return;
  k.penetration = in.real(t[kContactFieldsV8], what + " penetration");
  if (!(k.penetration >= 0) || (k.penetration > 0 && !(k.penetration <= -k.gap)))
    in.fail(what + ": the penetration must be in [0, the overlap]");
  if (version <= 9) return;
  k.pull = in.real(t[kContactFieldsV9], what + " pull-off force");
  if (!(k.pull >= 0)) in.fail(what + ": the pull-off force must not be negative");
  k.gap_shift = in.real(t[kContactFieldsV9 + 1], what + " gap shift");
}

std::vector<Contact> read_contacts(Reader &in, Tokens &t, long long version, int nb, int rows)
{
  const int contact_fields = contact_fields_of(version);
  in.keyword(t, "contacts", 1, "contacts <count>");
  const int nc = in.count(t[1], "contact count", 2 * contact_fields);
  std::vector<Contact> contacts(nc);
  for (int c = 0; c < nc; ++c) {
    const std::string what = "contact " + std::to_string(c);
    in.need(t, what + " of " + std::to_string(nc));
    in.fields(t, contact_fields, what);
    read_contact_frame(in, t, what, nb, rows, contacts[c]);
    read_contact_coefficients(in, t, what, version, contacts[c]);
  }
  return contacts;
}

std::vector<unsigned char> read_mask(Reader &in, Tokens &t, long long dofs)
{
  in.keyword(t, "mask", 1, "mask <count>");
  const int nmask = in.count(t[1], "mask count", 2);
  if (nmask != 0 && nmask != dofs)
    in.fail("mask count " + std::to_string(nmask) +
            " is neither 0 nor rows * contacts = " + std::to_string(dofs));
  std::vector<unsigned char> mask(nmask);
  for (int i = 0; i < nmask; ++i) {
    in.need(t, "mask entry " + std::to_string(i) + " of " + std::to_string(nmask));
    in.fields(t, 1, "mask entry " + std::to_string(i));
    const long long m = in.integer(t[0], "mask entry");
    if (m != 0 && m != 1) in.fail("mask entry must be 0 or 1, not " + std::to_string(m));
    mask[i] = static_cast<unsigned char>(m);
  }
  return mask;
}

Vector read_rhs(Reader &in, Tokens &t, long long dofs)
{
  in.keyword(t, "rhs", 1, "rhs <count>");
  const int nrhs = in.count(t[1], "rhs count", 2);
  if (nrhs != dofs)
    in.fail("rhs count " + std::to_string(nrhs) +
            " differs from rows * contacts = " + std::to_string(dofs));
  Vector rhs(nrhs);
  for (int i = 0; i < nrhs; ++i) {
    in.need(t, "rhs entry " + std::to_string(i) + " of " + std::to_string(nrhs));
    in.fields(t, 1, "rhs entry " + std::to_string(i));
    rhs[i] = in.real(t[0], "rhs entry " + std::to_string(i));
  }
  return rhs;
}

} // namespace

ContactSystem parse_system(std::string_view text)
{
  Reader in(text);
  Tokens t;
  const long long version = read_header(in, t);
  in.keyword(t, "rows", 1, "rows <3|6>");
  const long long rows = in.integer(t[1], "rows");
  if (rows != 3 && rows != 6) in.fail("rows must be 3 or 6, not " + std::to_string(rows));
  const SpookParams params = read_spook(in, t, version);
  long long owned = 0;
  std::vector<Body> bodies = read_bodies(in, t, owned);
  const int nb = static_cast<int>(bodies.size());
  std::vector<Contact> contacts = read_contacts(in, t, version, nb, static_cast<int>(rows));
  if (version <= 10) // split as the readers of these versions did: beyond the floor
    for (Contact &k : contacts)
      k.split =
          k.elastic[0] && k.penetration > params.penetration_floor * params.h * params.max_recovery;
  const long long dofs = rows * static_cast<long long>(contacts.size());
  const std::vector<unsigned char> mask = read_mask(in, t, dofs);
  const Vector rhs = read_rhs(in, t, dofs);

  in.keyword(t, "end", 0, "end");
  if (in.next(t)) in.fail("unexpected content after 'end': '" + excerpt(t[0]) + "'");

  try {
    ContactSystem sys(std::move(bodies), std::move(contacts), static_cast<int>(rows), params,
                      static_cast<int>(owned));
    if (!mask.empty()) sys.set_row_mask(mask);
    sys.set_rhs(rhs);
    return sys;
  } catch (const std::invalid_argument &e) {
    throw std::runtime_error(std::string("system file: invalid system: ") + e.what());
  }
}

ContactSystem read_system(std::istream &in)
{
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw std::runtime_error("system file: read error");
  return parse_system(text);
}

ContactSystem read_system_file(const std::string &path)
{
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open '" + path + "' for reading");
  try {
    return read_system(in);
  } catch (const std::runtime_error &e) {
    throw std::runtime_error("'" + path + "': " + e.what());
  }
}

namespace {

void write_coordinate(const std::string &path, const SparseMatrix &S, bool symmetric,
                      const char *comment)
{
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot open '" + path + "' for writing");
  out << "%%MatrixMarket matrix coordinate real " << (symmetric ? "symmetric" : "general") << "\n% "
      << comment << "\n";
  long nnz = 0;
  for (Eigen::Index j = 0; j < S.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(S, j); it; ++it) nnz += !symmetric || it.row() >= it.col();
  out << S.rows() << " " << S.cols() << " " << nnz << "\n";
  std::string s;
  for (Eigen::Index j = 0; j < S.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(S, j); it; ++it) {
      if (symmetric && it.row() < it.col()) continue; // lower triangle, as the format asks
      s = std::to_string(it.row() + 1) + " " + std::to_string(it.col() + 1) + " ";
      put_real(s, it.value());
      s += '\n';
      out << s;
    }
  out.close();
  check_stream(out, "'" + path + "'");
}

SparseMatrix diagonal_matrix(const Vector &d)
{
  SparseMatrix D(d.size(), d.size());
  D.reserve(Eigen::VectorXi::Ones(d.size()));
  for (Eigen::Index i = 0; i < d.size(); ++i) D.insert(i, i) = d[i];
  D.makeCompressed();
  return D;
}

} // namespace

void export_matrix_market(const ContactSystem &sys, const std::string &prefix)
{
  write_coordinate(prefix + "_G.mtx", assemble_G(sys), false,
                   "fibre_contact G: rows per contact x 6 per body (v, omega)");
  write_coordinate(prefix + "_Minv.mtx", diagonal_matrix(assemble_inv_mass(sys)), true,
                   "fibre_contact M^-1: 6 per body");
  write_coordinate(prefix + "_Sigma.mtx", diagonal_matrix(assemble_sigma(sys)), true,
                   "fibre_contact Sigma: rows per contact");
  write_coordinate(prefix + "_A.mtx", assemble_A(sys), true,
                   "fibre_contact A = G M^-1 G^T + Sigma");
  const std::string path = prefix + "_b.mtx";
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot open '" + path + "' for writing");
  out << "%%MatrixMarket matrix array real general\n% fibre_contact b (A lambda = b)\n"
      << sys.rhs().size() << " 1\n";
  std::string s;
  for (Eigen::Index i = 0; i < sys.rhs().size(); ++i) {
    s.clear();
    put_real(s, sys.rhs()[i]);
    s += '\n';
    out << s;
  }
  out.close();
  check_stream(out, "'" + path + "'");
}

} // namespace fibre
