// System files: exact round trips, one specific error per kind of damage, and Matrix Market
// export read back by an independent little parser and compared with the dense reference.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "fibre/algebra/spook.hpp"
#include "fibre/algebra/spook.hpp"
#include "fibre/io/system_io.hpp"
#include "fibre/scenes.hpp"
#include "reference.hpp"

using namespace fibre;

namespace {

// A pile with ghosts, a row mask, awkward numbers and a rhs that is not spook_rhs.
ContactSystem sample_system(int rows = 6)
{
  SceneParams p;
  p.rows = rows;
  p.spook.h = 1.0 / 3.0e3;
  p.spook.damping = 2.5;
  p.spook.max_recovery = 0.125;
  p.spook.bounce_speed = 0.25;
  const ContactSystem pile = pile_scene(25, p);
  std::vector<Body> bodies = pile.bodies();
  bodies[0].v = Vec3(-0.0, 1e-310, 0.1); // signed zero and a subnormal
  bodies[1].torque = Vec3(1e300, -1.0 / 7.0, 3.0);
  std::vector<Contact> contacts = pile.contacts();
  contacts[0].compliance = {1e-8, 2e-8, 3e-8, 4e-8, 5e-8, 6e-8};
  contacts[1].friction = FrictionParams{0.3, 1.0 / 3.0, 0.0};  // per contact since version 2
  contacts[1].restitution = 0.7;                               // since version 3
  contacts[2].elastic = {true, true, true, false, true, true}; // since version 4 (5: row 0)
  contacts[2].spring = {0.0, 1.0 / 3.0, -2e-7, 0.0, 1e-300, -0.5};
  contacts[2].spring_damping = {-1.0, -1.0, -1.0, 0.0, 56.8, 56.8}; // since version 7
  contacts[2].implicit_normal = true;                               // since version 8
  contacts[2].gap = -0.01;
  contacts[2].penetration = 0.75 * 0.01; // since version 9
  contacts[2].split = true;              // since version 11
  contacts[3].pull = 2.5;                // since version 10
  contacts[3].gap_shift = -1.0 / 3.0;
  for (Contact &c : contacts) // an obstacle sphere, since version 6
    if (c.is_wall()) {
      c.wall_radius = 0.375;
      break;
    }
  ContactSystem sys(bodies, contacts, rows, p.spook, pile.num_bodies() - 4);
  std::vector<unsigned char> mask(sys.contact_dofs(), 1);
  for (std::size_t r = 2; r < mask.size(); r += 7) mask[r] = 0;
  sys.set_row_mask(mask);
  Vector rhs = spook_rhs(sys);
  rhs[1] = std::sqrt(2.0);
  sys.set_rhs(rhs);
  return sys;
}

std::string to_text(const ContactSystem &sys)
{
  std::ostringstream out;
  write_system(out, sys);
  return out.str();
}

void expect_identical(const ContactSystem &a, const ContactSystem &b)
{
  ASSERT_EQ(a.rows(), b.rows());
  ASSERT_EQ(a.num_bodies(), b.num_bodies());
  ASSERT_EQ(a.num_contacts(), b.num_contacts());
  EXPECT_EQ(a.num_owned_bodies(), b.num_owned_bodies());
  EXPECT_EQ(a.params().h, b.params().h);
  EXPECT_EQ(a.params().damping, b.params().damping);
  EXPECT_EQ(a.params().max_recovery, b.params().max_recovery);
  EXPECT_EQ(a.params().bounce_speed, b.params().bounce_speed);
  // Bitwise: memcmp-like equality, so that -0.0 and 0.0 differ.
  auto same = [](double x, double y) { return std::signbit(x) == std::signbit(y) && x == y; };
  auto same3 = [&](const Vec3 &x, const Vec3 &y) {
    return same(x[0], y[0]) && same(x[1], y[1]) && same(x[2], y[2]);
  };
  for (int i = 0; i < a.num_bodies(); ++i) {
    const Body &p = a.bodies()[i], &q = b.bodies()[i];
    EXPECT_TRUE(same(p.mass, q.mass) && same(p.radius, q.radius) && same3(p.x, q.x) &&
                same3(p.v, q.v) && same3(p.omega, q.omega) && same3(p.force, q.force) &&
                same3(p.torque, q.torque))
        << "body " << i;
  }
  for (int c = 0; c < a.num_contacts(); ++c) {
    const Contact &p = a.contacts()[c], &q = b.contacts()[c];
    EXPECT_TRUE(p.a == q.a && p.b == q.b && same3(p.normal, q.normal) && same3(p.t1, q.t1) &&
                same3(p.t2, q.t2) && same3(p.point, q.point) && same(p.gap, q.gap) &&
                p.compliance == q.compliance && p.friction.mu == q.friction.mu &&
                p.friction.mu_roll == q.friction.mu_roll &&
                p.friction.mu_twist == q.friction.mu_twist && p.restitution == q.restitution &&
                p.damping == q.damping && p.wall_v == q.wall_v && p.wall_omega == q.wall_omega &&
                p.elastic == q.elastic && p.spring == q.spring && p.wall_radius == q.wall_radius &&
                p.spring_damping == q.spring_damping && p.implicit_normal == q.implicit_normal &&
                p.penetration == q.penetration && p.split == q.split && p.pull == q.pull &&
                p.gap_shift == q.gap_shift)
        << "contact " << c;
  }
  EXPECT_EQ(a.row_mask(), b.row_mask());
  ASSERT_EQ(a.rhs().size(), b.rhs().size());
  for (Eigen::Index i = 0; i < a.rhs().size(); ++i) EXPECT_TRUE(same(a.rhs()[i], b.rhs()[i]));
  EXPECT_EQ(a.sigma(), b.sigma());
  EXPECT_EQ(a.inv_mass(), b.inv_mass());
}

std::vector<std::string> lines_of(const std::string &text)
{
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

std::string join(const std::vector<std::string> &lines)
{
  std::string s;
  for (const std::string &l : lines) s += l + "\n";
  return s;
}

// Index of the first line that starts with `prefix`.
std::size_t find_line(const std::vector<std::string> &lines, const std::string &prefix)
{
  for (std::size_t i = 0; i < lines.size(); ++i)
    if (lines[i].rfind(prefix, 0) == 0) return i;
  ADD_FAILURE() << "no line starts with " << prefix;
  return 0;
}

// Replaces token k of a line.
std::string with_token(const std::string &line, std::size_t k, const std::string &value)
{
  std::istringstream in(line);
  std::vector<std::string> t;
  for (std::string w; in >> w;) t.push_back(w);
  t.at(k) = value;
  std::string s;
  for (std::size_t i = 0; i < t.size(); ++i) s += (i ? " " : "") + t[i];
  return s;
}

// parse_system must throw std::runtime_error whose message contains every `parts` string.
void expect_error(const std::string &text, std::initializer_list<std::string> parts)
{
  try {
    parse_system(text);
    ADD_FAILURE() << "accepted a malformed system; expected: " << *parts.begin();
  } catch (const std::runtime_error &e) {
    for (const std::string &p : parts)
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos)
          << "message '" << e.what() << "' lacks '" << p << "'";
  }
}

std::string temp_path(const std::string &name)
{
  return "/tmp/fibre_io_" + std::to_string(getpid()) + "_" + name;
}

} // namespace

TEST(SystemIo, RoundTripIsExact)
{
  for (int rows : {6, 3}) {
    const ContactSystem sys = sample_system(rows);
    const std::string text = to_text(sys);
    EXPECT_EQ(text.rfind("fibre_contact_system 11\n", 0), 0u);
    const ContactSystem back = parse_system(text);
    expect_identical(sys, back);
    EXPECT_EQ(to_text(back), text); // and the writer is deterministic
  }
}

// An older version of the sample: the spook line and each contact line lose their last
// `drop_spook` and `drop_contact` values.
std::string older_version(const ContactSystem &sys, int version, int drop_spook, int drop_contact)
{
  std::istringstream in(to_text(sys));
  std::string out, line;
  bool in_contacts = false;
  int left = 0;
  const auto drop = [](std::string &l, int n) {
    for (int k = 0; k < n; ++k) l = l.substr(0, l.rfind(' '));
  };
  while (std::getline(in, line)) {
    if (line.rfind("spook ", 0) == 0) {
      drop(line, drop_spook);
    } else if (line.rfind("contacts ", 0) == 0) {
      in_contacts = true;
      left = sys.num_contacts();
    } else if (in_contacts && left > 0) {
      if (version < 11) { // no implicit normal rows before 8 (bit 6 of the elastic rows, token
        // 32), no split penetrations before 11 (bit 7): cleared
        std::vector<std::string> tokens;
        std::istringstream words(line);
        for (std::string w; words >> w;) tokens.push_back(w);
        tokens[32] = std::to_string(std::stoi(tokens[32]) & (version < 8 ? 63 : 127));
        line.clear();
        for (const std::string &w : tokens) line += (line.empty() ? "" : " ") + w;
      }
      drop(line, drop_contact);
      --left;
    }
    out += line + "\n";
  }
  out.replace(0, std::string("fibre_contact_system " + std::to_string(kSystemFormatVersion)).size(),
              "fibre_contact_system " + std::to_string(version));
  return out;
}

// Version 1 files (no friction per contact) and version 2 files (no restitution) still read,
// with the defaults; a negative coefficient or a restitution above 1 is an error.
TEST(SystemIo, OlderVersionsAndCoefficientFields)
{
  const ContactSystem sys = sample_system();
  const ContactSystem v1 = parse_system(older_version(sys, 1, 2, 26));
  ASSERT_EQ(v1.num_contacts(), sys.num_contacts());
  EXPECT_EQ(v1.contacts()[1].friction.mu, FrictionParams{}.mu);
  EXPECT_EQ(v1.contacts()[1].friction.mu_roll, FrictionParams{}.mu_roll);
  EXPECT_EQ(v1.contacts()[1].restitution, 0.0);
  EXPECT_EQ(v1.contacts()[0].compliance, sys.contacts()[0].compliance);
  EXPECT_EQ(v1.params().max_recovery, 0.0);
  const ContactSystem v2 = parse_system(older_version(sys, 2, 1, 23));
  EXPECT_EQ(v2.contacts()[1].friction.mu, 0.3);
  EXPECT_EQ(v2.contacts()[1].restitution, 0.0);
  EXPECT_EQ(v2.params().max_recovery, 0.125);
  EXPECT_EQ(v2.params().bounce_speed, 0.0);
  const ContactSystem v3 = parse_system(older_version(sys, 3, 0, 15));
  EXPECT_EQ(v3.contacts()[1].restitution, 0.7);
  EXPECT_FALSE(v3.contacts()[2].any_elastic());
  // version 4 knows the elastic rows 1..5 only: bit 5 (the normal row) is an error there,
  // and without it the normal row reads rigid
  const std::string v4_text = older_version(sys, 4, 0, 9);
  expect_error(v4_text, {"contact 2:", "rows 1 to 5, in [0, 31]"});
  const std::size_t mask_at = v4_text.find(" 59 ", v4_text.find("contacts "));
  ASSERT_NE(mask_at, std::string::npos); // contact 2's mask: rows 0, 1, 2, 4, 5
  const ContactSystem v4 =
      parse_system(v4_text.substr(0, mask_at) + " 27 " + v4_text.substr(mask_at + 4));
  EXPECT_FALSE(v4.contacts()[2].elastic[0]);
  EXPECT_TRUE(v4.contacts()[2].elastic[1]);
  EXPECT_EQ(v3.contacts()[2].spring, (std::array<double, kMaxRows>{}));
  // version 5 has no obstacle radius: every wall reads flat
  const ContactSystem v5 = parse_system(older_version(sys, 5, 0, 9));
  int obstacles = 0;
  for (int c = 0; c < sys.num_contacts(); ++c) {
    obstacles += sys.contacts()[c].wall_radius > 0;
    EXPECT_EQ(v5.contacts()[c].wall_radius, 0.0);
  }
  EXPECT_EQ(obstacles, 1);
  // version 6 has no springs' own damping: every row takes the contact's
  const ContactSystem v6 = parse_system(older_version(sys, 6, 0, 8));
  EXPECT_EQ(v6.contacts()[2].spring_damping,
            (std::array<double, kMaxRows>{-1, -1, -1, -1, -1, -1}));
  EXPECT_EQ(v6.contacts()[2].wall_radius, sys.contacts()[2].wall_radius);
  // version 9 has no cohesion
  const ContactSystem v9 = parse_system(older_version(sys, 9, 0, 2));
  EXPECT_EQ(v9.contacts()[3].pull, 0.0);
  EXPECT_EQ(v9.contacts()[3].gap_shift, 0.0);
  EXPECT_EQ(v9.contacts()[2].penetration, sys.contacts()[2].penetration);
  // before version 11 an elastic penetration is split beyond the floor's steps of recovery
  const ContactSystem v10 = parse_system(older_version(sys, 10, 0, 0));
  const SpookParams &q = v10.params();
  EXPECT_EQ(v10.contacts()[2].split,
            v10.contacts()[2].penetration > q.penetration_floor * q.h * q.max_recovery);
  EXPECT_TRUE(parse_system(to_text(sys)).contacts()[2].split);
  // version 8 has no penetrations
  const ContactSystem v8 = parse_system(older_version(sys, 8, 0, 3));
  EXPECT_EQ(v8.contacts()[2].penetration, 0.0);
  EXPECT_EQ(v8.contacts()[2].spring_damping, sys.contacts()[2].spring_damping);
  // a concave wall (a negative radius) is version 7's: version 6 rejects it
  const std::string v6_text = older_version(sys, 6, 0, 8);
  const std::size_t convex = v6_text.find(" 0.375\n");
  ASSERT_NE(convex, std::string::npos);
  expect_error(v6_text.substr(0, convex) + " -0.375\n" + v6_text.substr(convex + 7),
               {"the wall radius must be >= 0"});
  // the first contact line with a negative twisting coefficient, a restitution of 2 and a
  // negative damping other than -1
  const std::string text = to_text(sys);
  const std::size_t at = text.find("contacts ");
  const std::size_t begin = text.find('\n', at) + 1, end = text.find('\n', begin);
  std::vector<std::string> fields;
  std::istringstream words(text.substr(begin, end - begin));
  for (std::string w; words >> w;) fields.push_back(w);
  ASSERT_EQ(fields.size(), 47u);
  const auto with = [&](std::size_t index, const std::string &value) {
    std::vector<std::string> f = fields;
    f[index] = value;
    std::string line;
    for (const std::string &w : f) line += (line.empty() ? "" : " ") + w;
    return text.substr(0, begin) + line + text.substr(end);
  };
  expect_error(with(23, "-1"), {"contact 0:", "mu_twist must not be negative"});
  expect_error(with(24, "2"), {"contact 0:", "restitution must be in [0, 1]"});
  expect_error(with(25, "-2"), {"contact 0:", "damping must be non-negative"});
  if (sys.contacts()[0].is_wall()) // inside a region of radius 2
    EXPECT_EQ(parse_system(with(38, "-2")).contacts()[0].wall_radius, -2.0);
  else
    expect_error(with(38, "-2"), {"contact 0:", "0 for a pair"});
  EXPECT_EQ(parse_system(with(25, "-1")).contacts()[0].damping, -1.0);
  expect_error(with(32, "256"), {"contact 0:", "elastic rows must be a bit mask"});
  expect_error(with(32, "128"), {"contact 0:", "a split penetration's row must be elastic"});
  EXPECT_TRUE(parse_system(with(32, "160")).contacts()[0].split); // since version 11
  expect_error(with(32, "64"), {"contact 0:", "an implicit normal row must be elastic"});
  EXPECT_TRUE(parse_system(with(32, "96")).contacts()[0].implicit_normal); // since version 8
  expect_error(with(33, "0.5"), {"contact 0:", "a spring on row 1, which is not elastic"});
  const Contact elastic = parse_system(with(32, "9")).contacts()[0]; // rows 1 and 4
  EXPECT_TRUE(elastic.elastic[1] && elastic.elastic[4] && !elastic.elastic[2]);
  expect_error(with(43, "-2"), {"contact 0:", "a spring's damping must be non-negative"});
  EXPECT_EQ(parse_system(with(43, "3.5")).contacts()[0].spring_damping[5], 3.5);
  expect_error(with(44, "-1e-3"), {"contact 0:", "the penetration must be in [0, the overlap]"});
  expect_error(with(44, "10"), {"contact 0:", "the penetration must be in [0, the overlap]"});
  expect_error(with(45, "-1"), {"contact 0:", "the pull-off force must not be negative"});
  EXPECT_EQ(parse_system(with(46, "0.25")).contacts()[0].gap_shift, 0.25);
  if (sys.contacts()[0].is_wall()) return;
  expect_error(with(26, "1"), {"contact 0:", "a pair cannot have a wall velocity"});
}

TEST(SystemIo, FileRoundTripAndMissingFile)
{
  const ContactSystem sys = sample_system();
  const std::string path = temp_path("sys.txt");
  write_system_file(path, sys);
  expect_identical(sys, read_system_file(path));
  std::remove(path.c_str());
  try {
    read_system_file(path);
    ADD_FAILURE() << "read a missing file";
  } catch (const std::runtime_error &e) {
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
  EXPECT_THROW(write_system_file("/nonexistent_dir/x.txt", sys), std::runtime_error);
}

TEST(SystemIo, EmptySystemAndCommentsRoundTrip)
{
  const ContactSystem empty({}, {}, 6, SpookParams{});
  expect_identical(empty, parse_system(to_text(empty)));
  // Comments and blank lines anywhere, CRLF line ends.
  std::string text = to_text(sample_system());
  std::string crlf;
  for (char c : text) crlf += c == '\n' ? std::string("\r\n\n# note\n") : std::string(1, c);
  expect_identical(sample_system(), parse_system(crlf));
}

TEST(SystemIo, EachMalformedInputGetsItsOwnError)
{
  const ContactSystem sys = sample_system();
  const std::string text = to_text(sys);
  const std::vector<std::string> L = lines_of(text);
  const std::size_t bodies = find_line(L, "bodies "), contacts = find_line(L, "contacts ");
  const std::size_t mask = find_line(L, "mask "), rhs = find_line(L, "rhs ");
  auto edit = [&](std::size_t line, const std::string &content) {
    std::vector<std::string> v = L;
    v[line] = content;
    return join(v);
  };
  auto line_tag = [](std::size_t index) { return "line " + std::to_string(index + 1) + ":"; };

  expect_error("", {"line 1:", "unexpected end of input", "header"});
  expect_error(edit(0, "fibre_contact_sistem 1"), {"line 1:", "not a fibre_contact system"});
  expect_error(edit(0, "fibre_contact_system 12"), {"unsupported format version 12"});
  expect_error(edit(0, "fibre_contact_system one"), {"'one' is not an integer"});
  expect_error(edit(2, "rows 4"), {"rows must be 3 or 6"});
  expect_error(edit(3, "spook 0 2"), {"time step h must be positive"});
  expect_error(edit(3, "spook"), {"expected 'spook <h> <damping> [max_recovery [bounce_speed]]'"});
  expect_error(edit(3, "spook 0.1 2 -1"), {"max_recovery must be non-negative"});

  // Truncation: between lines, in the middle of one, and early (a count then claims more
  // than the rest of the input holds).
  {
    const long n = static_cast<long>(sys.contact_dofs());
    std::vector<std::string> v(L.begin(), L.begin() + rhs + 1 + n / 2);
    expect_error(join(v), {"unexpected end of input, expected rhs entry " + std::to_string(n / 2) +
                           " of " + std::to_string(n)});
    const std::size_t last = mask - 1; // the last contact line
    const std::string cut = join(std::vector<std::string>(L.begin(), L.begin() + last)) +
                            L[last].substr(0, L[last].size() / 2);
    expect_error(cut, {line_tag(last), "contact " + std::to_string(sys.num_contacts() - 1) +
                                           ": expected 47 values"});
    expect_error(text.substr(0, text.size() - 4), {"unexpected end of input", "'end'"});
    std::vector<std::string> early(L.begin(), L.begin() + bodies + 3);
    expect_error(join(early), {line_tag(bodies), "body count 25 is more than the rest"});
  }

  // Counts: mismatched and absurd.
  expect_error(edit(bodies, "bodies " + std::to_string(sys.num_bodies() + 1) + " 0"),
               {"body " + std::to_string(sys.num_bodies()) + ": expected 17 values"});
  expect_error(edit(bodies, "bodies 3 0"), {"expected 'contacts <count>'"});
  expect_error(edit(bodies, "bodies 4000000000 0"),
               {line_tag(bodies), "body count 4000000000 is more than the rest of the input"});
  expect_error(edit(bodies, "bodies 100000 0"), {"more than the rest of the input can hold"});
  expect_error(edit(bodies, "bodies -1 0"), {"body count -1 is negative"});
  expect_error(edit(bodies, "bodies 25 26"), {"owned body count 26 is not in [0, 25]"});
  expect_error(edit(contacts, "contacts 99999999999999999999"), {"is not an integer"});
  expect_error(edit(mask, "mask 5"), {"mask count 5 is neither 0 nor rows * contacts"});
  expect_error(edit(rhs, "rhs 3"), {"rhs count 3 differs from rows * contacts"});
  expect_error(edit(mask + 1, "2"), {"mask entry must be 0 or 1"});

  // Values: non-numeric, non-finite, out of range, physically invalid.
  expect_error(edit(bodies + 1, with_token(L[bodies + 1], 0, "abc")),
               {line_tag(bodies + 1), "'abc' is not a number (body 0 mass)"});
  expect_error(edit(bodies + 2, with_token(L[bodies + 2], 3, "nan")),
               {"non-finite value 'nan' (body 1 position)"});
  expect_error(edit(bodies + 2, with_token(L[bodies + 2], 6, "-inf")), {"non-finite value"});
  expect_error(edit(bodies + 2, with_token(L[bodies + 2], 6, "1e999")), {"out of range"});
  expect_error(edit(bodies + 1, with_token(L[bodies + 1], 0, "-1")),
               {"body 0: mass must be positive"});
  expect_error(edit(rhs + 1, "0x1p3"), {"'0x1p3' is not a number (rhs entry 0)"});
  expect_error(edit(rhs + 1, "1.0 2.0"), {"rhs entry 0: expected 1 values, found 2"});

  // Contacts: body indices, frames, compliance.
  const std::string c0 = L[contacts + 1];
  expect_error(edit(contacts + 1, with_token(c0, 0, "25")),
               {"contact 0: body index 25 out of range [0, 25)"});
  expect_error(edit(contacts + 1, with_token(c0, 1, "-2")),
               {"contact 0: body index -2 out of range [-1, 25)"});
  expect_error(edit(contacts + 1, with_token(with_token(c0, 0, "3"), 1, "3")),
               {"contact 0: a body in contact with itself"});
  expect_error(edit(contacts + 1, with_token(c0, 2, "2")), {"contact 0 normal is not a unit"});
  expect_error(edit(contacts + 1, with_token(c0, 15, "0")),
               {"contact 0: compliance of row 0 must be positive"});
  expect_error(edit(contacts + 1, c0 + " 7"), {"contact 0: expected 47 values, found 48"});

  // Anything after the end, and binary junk.
  expect_error(text + "bodies 1 1\n", {"unexpected content after 'end'"});
  expect_error(std::string("\x7f\x45\x4c\x46\x02\x01\x01\0\0", 9), {"not a fibre_contact system"});
}

TEST(SystemIo, FrameMustBeOrthonormal)
{
  const std::string text = to_text(sample_system());
  std::vector<std::string> L = lines_of(text);
  const std::size_t c = find_line(L, "contacts ") + 1;
  // t1 := n: unit, but not orthogonal to n.
  std::istringstream in(L[c]);
  std::vector<std::string> t;
  for (std::string w; in >> w;) t.push_back(w);
  for (int k = 0; k < 3; ++k) L[c] = with_token(L[c], 5 + k, t[2 + k]);
  expect_error(join(L), {"contact 0: normal, t1 and t2 are not orthogonal"});
}

// ---- Matrix Market ----

namespace {

struct Market {
  std::string header;
  Eigen::MatrixXd M;
};

// An independent reader for the two Matrix Market kinds written (coordinate, array).
Market read_market(const std::string &path)
{
  std::ifstream in(path);
  Market m;
  std::getline(in, m.header);
  std::string line;
  while (std::getline(in, line) && line[0] == '%') {
  }
  std::istringstream size(line);
  long rows = 0, cols = 0, nnz = 0;
  size >> rows >> cols;
  m.M = Eigen::MatrixXd::Zero(rows, cols);
  if (m.header.find("array") != std::string::npos) {
    for (long j = 0; j < cols; ++j)
      for (long i = 0; i < rows; ++i) in >> m.M(i, j);
    return m;
  }
  size >> nnz;
  const bool symmetric = m.header.find("symmetric") != std::string::npos;
  for (long e = 0; e < nnz; ++e) {
    long i, j;
    double v;
    in >> i >> j >> v;
    EXPECT_TRUE(!symmetric || i >= j) << "symmetric files hold the lower triangle";
    m.M(i - 1, j - 1) = v;
    if (symmetric) m.M(j - 1, i - 1) = v;
  }
  EXPECT_TRUE(static_cast<bool>(in)) << path << " is short";
  return m;
}

} // namespace

TEST(SystemIo, MatrixMarketExportMatchesDenseReference)
{
  const ContactSystem sys = sample_system();
  const std::string prefix = temp_path("mm");
  export_matrix_market(sys, prefix);
  const Market G = read_market(prefix + "_G.mtx"), Minv = read_market(prefix + "_Minv.mtx");
  const Market S = read_market(prefix + "_Sigma.mtx"), A = read_market(prefix + "_A.mtx");
  const Market b = read_market(prefix + "_b.mtx");
  EXPECT_EQ(G.header, "%%MatrixMarket matrix coordinate real general");
  EXPECT_EQ(A.header, "%%MatrixMarket matrix coordinate real symmetric");
  EXPECT_EQ(b.header, "%%MatrixMarket matrix array real general");
  EXPECT_EQ(G.M, test::dense_G(sys));
  EXPECT_EQ(Minv.M, test::dense_Minv(sys));
  EXPECT_EQ(Eigen::VectorXd(S.M.diagonal()), test::dense_sigma(sys));
  const test::Dense Aref = test::dense_A(sys);
  EXPECT_LT((A.M - Aref).norm(), 1e-13 * Aref.norm());
  ASSERT_EQ(b.M.cols(), 1);
  EXPECT_EQ(Eigen::VectorXd(b.M.col(0)), sys.rhs());
  for (const char *f : {"_G", "_Minv", "_Sigma", "_A", "_b"})
    std::remove((prefix + f + ".mtx").c_str());
  EXPECT_THROW(export_matrix_market(sys, "/nonexistent_dir/x"), std::runtime_error);
}
