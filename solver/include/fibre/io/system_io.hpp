// Whole contact systems as text files, and Matrix Market export for SciPy/MATLAB users.
//
// Format "fibre_contact_system", version 1 (also in doc/system_format.md). Line oriented,
// tokens separated by blanks; blank lines and lines starting with '#' are ignored anywhere.
// Reals are written like printf's %.17g (locale independent), which reads back bit for bit.
//
//   fibre_contact_system 1
//   rows <3|6>
//   spook <h> <damping>
//   bodies <count> <num_owned>
//   <mass> <radius> <x y z> <vx vy vz> <wx wy wz> <fx fy fz> <tx ty tz>    count lines
//   contacts <count>
//   <a> <b> <n xyz> <t1 xyz> <t2 xyz> <p xyz> <gap> <eps_0 .. eps_5>        count lines
//   mask <count>          0 (every row active) or rows * contacts; then count lines of 0/1
//   rhs <count>           rows * contacts; then count lines, one value each
//   end
//
// Bodies [0, num_owned) are owned, the rest ghosts. Contact b is -1 for a wall. All six
// compliances are stored whatever rows is (the unused ones are kept for an exact round trip).
//
// The reader validates everything and throws std::runtime_error naming the line and the
// problem: bad header or version, truncation, wrong token counts, non-numeric or non-finite
// values, out-of-range body indices, counts that disagree or that the remaining input cannot
// hold (so absurd counts never allocate), and anything ContactSystem itself rejects.
#pragma once

#include <iosfwd>
#include <string>
#include <string_view>

#include "fibre/core/system.hpp"

namespace fibre {

// 2: friction per contact; 3: restitution, damping and wall velocity per contact and the bounce
// speed; 4, 5: elastic rows and their springs; 6: an obstacle's radius; 7: the springs' own
// damping; 8: implicit normal rows. Every older version is read (doc/system_format.md).
inline constexpr int kSystemFormatVersion = 11;

void write_system(std::ostream &out, const ContactSystem &sys);
// Throws std::runtime_error when the file cannot be written.
void write_system_file(const std::string &path, const ContactSystem &sys);

ContactSystem parse_system(std::string_view text);
ContactSystem read_system(std::istream &in);
// Throws std::runtime_error when the file cannot be read, or on any error in it.
ContactSystem read_system_file(const std::string &path);

// Writes prefix_G.mtx (coordinate real general), prefix_Minv.mtx, prefix_Sigma.mtx and
// prefix_A.mtx (coordinate real symmetric, lower triangle) and prefix_b.mtx (array real
// general, the system's rhs). Indices are 1-based, as Matrix Market wants. This process's
// local system only. Throws std::runtime_error when a file cannot be written.
void export_matrix_market(const ContactSystem &sys, const std::string &prefix);

} // namespace fibre
