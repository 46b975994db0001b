"""Writes yang_mills_su2.toml: SU(2) Yang-Mills mechanics with spatially homogeneous
fields (python3 examples/singular/make_yang_mills_su2.py > examples/singular/yang_mills_su2.toml).

A_i^a (i = 1..3 space, a = 1..3 colour) and A_0^a (named B1..B3); the electric field
E_i^a = A_i^a' + g eps_abc A_0^b A_i^c, the magnetic F_ij^a = g eps_abc A_i^b A_j^c;
L = sum E^2/2 - sum_{i,j,a} F_ij^a^2/4 (the quartic potential).
"""

import sympy as sp

g = sp.Symbol("g")
A = [[sp.Symbol(f"A{i}{a}") for a in range(1, 4)] for i in range(1, 4)]
A0 = [sp.Symbol(f"B{a}") for a in range(1, 4)]
eps = sp.LeviCivita
E = [[sp.Symbol(f"A{i + 1}{a}_dot") + g * sum(eps(a, b, c) * A0[b - 1] * A[i][c - 1]
                                             for b in range(1, 4) for c in range(1, 4))
      for a in range(1, 4)] for i in range(3)]
F2 = sum(sum(g * eps(a, b, c) * A[i][b - 1] * A[j][c - 1]
             for b in range(1, 4) for c in range(1, 4))**2
         for i in range(3) for j in range(3) for a in range(1, 4))
L = sum(E[i][a]**2 for i in range(3) for a in range(3)) / 2 - F2 / 4
coords = [s.name for row in A for s in row] + [s.name for s in A0]
print("""# SU(2) Yang-Mills mechanics: the gauge field constant in space (12 coordinates: A_i^a,
# and A_0^a named B1..B3, which has no velocity in L). Written by make_yang_mills_su2.py.
#
# nhham classify: W has rank 9 of 12; the primaries p_B1, p_B2, p_B3 = 0 have as
# secondaries Gauss's law G^a = eps_abc A_i^b p_Ai^c = 0 (the colour rotations of the
# A_i); all six first class (the G^a close among themselves), 12 - 6 = 6 degrees of
# freedom; three gauge generators eps_a_dot p_Ba + eps_a (G^a + g eps_abc B^b p_Bc), the
# last term the non-abelian one.
# nhham compare: the chain on TQ (q' = v built in) ends on a manifold of dimension 21,
# which Leg maps onto the final one of T*Q (dimension 18), motions included.
# simulate: in the temporal gauge B^a = 0 ([gauge]) the multipliers u_a = B^a' are fixed
# (0) and Gauss's law is kept; diagonal fields A_i^a = delta_ia a_i stay diagonal and follow
# the x^2 y^2 model a_1'' = -g^2 a_1 (a_2^2 + a_3^2) (and cyclically), energy conserved.
# linearize (no [steady]), bench, sweep, reduce, hamiltonize: refused (exit 2).""")
print('name = "SU(2) Yang-Mills mechanics (homogeneous fields)"')
print("coordinates = [" + ", ".join(f'"{c}"' for c in coords) + "]")
print(f'lagrangian = "{sp.expand(L)}"')
print("\n[parameters]\ng = 1.0")
print("\n# the temporal gauge A_0 = 0")
print('[gauge]\nconditions = ["B1", "B2", "B3"]')
diagonal = {"A11": 1.0, "A22": 0.5, "A33": 0.0}
rates = {"A33_dot": 0.8}
print("\n# diagonal fields (Gauss's law holds): the x^2 y^2 model")
print("[initial]")
for c in coords:
    print(f"{c} = {diagonal.get(c, 0.0)}")
for c in coords[:9]:
    print(f"{c}_dot = {rates.get(c + '_dot', 0.0)}")
