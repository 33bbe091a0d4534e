"""A residual table over *pairs* corrects a formation of three (issue 23 part 6, docs/ell.md "Converged saving"):
in an echelon near the wake plane, the coarse lattice with the sheet law plus the sum of the pairs' residuals
(nseg 80 minus nseg 10, each pair alone) reproduces the nseg-80 savings of the three together; without the
correction the sheet law is several percent off and the thesis's discrete legs tens of percent."""

from formation_env.verification.converged_saving import pairwise_residual_errors


def test_pair_residuals_add_up_in_an_echelon_of_three():
    rows = pairwise_residual_errors(trials=3, seed=11)
    for r in rows:
        assert r["pairwise"] < 0.01, r  # measured <= 0.5 % over 12 random echelons
        assert r["base"] > 3 * r["pairwise"], r  # the correction does the work
    assert max(r["thesis"] for r in rows) > 0.05  # the ripple the table is for
