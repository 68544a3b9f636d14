"""tightknot: tight physical knots in elastic rods.

Discrete elastic rods (Bergou et al. 2008, 2010) with kernels in NVIDIA Warp, a
radial-compliance self-contact layer, knot scenes and measurements of the reference
study (Johanns et al., Extreme Mech. Lett. 2021), and a small 3D solid FEM cross-check.
SI units everywhere inside; non-dimensional numbers only in measurements and plots.
"""

__version__ = "0.1.0"
