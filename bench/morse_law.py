"""Turns the plugin `pdyn new pair morse` wrote into a Morse pair force, as
an author following docs/pairs.md would: only the law's physics, its
parameters and its description change; every other line of the template,
its evaluate_beyond_cutoff declaration included, stays as the template wrote
it. Used by bench/morse_template_vs_lammps.sh.

    python3 bench/morse_law.py out/morse_template/morse/morse.cpp
"""
import sys

path = sys.argv[1]
text = open(path).read()


def swap(old, new):
    """Replaces the template's text `old`, which must be there once."""
    global text
    if text.count(old) != 1:
        sys.exit(f"morse_law.py: the template changed: {old!r} is not in {path} once")
    text = text.replace(old, new)


swap("""  double eps, rc;  // J, m""", """  double d0, alpha, r0;  // J, 1/m, m""")
swap("""    const double r = std::sqrt(r2);
    const double s = 1.0 - r / rc;
    // At r = 0 the force's direction is undefined and its magnitude finite:
    // no force, the energy's maximum.
    return {eps * s * s, r > 0.0 ? 2.0 * eps * s / (rc * r) : 0.0};""",
     """    // Morse: U = D0 (e^2 - 2 e), e = exp(-alpha (r - r0)); -U'(r)/r =
    // 2 alpha D0 (e^2 - e) / r, as LAMMPS's pair_style morse. At r = 0 the
    // force's direction is undefined: no force, as the template says.
    const double r = std::sqrt(r2);
    const double e = std::exp(-alpha * (r - r0));
    return {d0 * (e * e - 2.0 * e), r > 0.0 ? 2.0 * alpha * d0 * (e * e - e) / r : 0.0};""")
# Unshifted, as LAMMPS's: U(rc) is not 0, so the law declares nothing there.
swap("""  bool continuous_at_cutoff() const { return true; }\n""", "")
swap("""  d.description = "soft repulsion U = eps (1 - r/rc)^2 between particles closer than rc";""",
     """  d.description = "Morse U = D0 (exp(-2 a (r - r0)) - 2 exp(-a (r - r0))) within rc";""")
swap("""      pdyn::param::real("eps", 1.0, "J", "strength: the energy of two coincident particles")
          .at_least(0),""",
     """      pdyn::param::real("d0", 1.0, "J", "well depth D0").at_least(0),
      pdyn::param::real("alpha", 6.0, "1/m", "stiffness a").greater_than(0),
      pdyn::param::real("r0", 1.122462048309373, "m", "equilibrium distance").greater_than(0),""")
swap("""        Law{p.real("eps"), rc}, rc, skin,""",
     """        Law{p.real("d0"), p.real("alpha"), p.real("r0")}, rc, skin,""")
open(path, "w").write(text)
