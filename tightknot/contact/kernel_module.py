"""The Warp module that holds the contact layer's kernels.

Warp compiles a module as one unit and recompiles all of it when a kernel is added, so the
broad phase, the step bound and the pair kernel's variants (each defined beside its
launcher) share one module, filled at import. Loops are not unrolled (``max_unroll`` 1):
unrolling the pair kernel's 4 x 4 vertex blocks makes the module slow to compile; no
backward (adjoint) code is generated: the contact layer writes its derivatives by hand (and
the pair kernel's accumulating wp.funcs take ``wp.ref`` parameters, which Warp allows only
without it).
"""

from __future__ import annotations

import warp as wp

#: Name of the Warp module of the contact kernels.
KERNEL_MODULE = "tightknot.contact.kernel_module"

wp.set_module_options({"max_unroll": 1, "enable_backward": False}, module=KERNEL_MODULE)
