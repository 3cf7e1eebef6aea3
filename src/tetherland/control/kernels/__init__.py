"""The control laws, one module per law, each plain and compiled side by side (numba).

* :mod:`.mixer`: allocation (6.19) with priority saturation and speed commands;
* :mod:`.free_flight`: geometric position + SO(3) attitude control (Lee et al. 2010);
* :mod:`.tracker`: the contact-free tracker (the free-flight law with flatness
  feed-forward, a hover-only integral and motor-lag compensation);
* :mod:`.hierarchical`: the tethered law Gamma_HC^b (docs/theory.md section 7);
* :mod:`.dfl`: the tethered law Gamma_DFL^b, with its model (:mod:`.dfl_model`, CasADi),
  the kernel generated from it (:mod:`.dfl_terms`) and the generator (:mod:`.dfl_codegen`);
* :mod:`.so3`: the pieces the compiled laws share (3x3 products, the attitude law, the
  cable-torque cancellation, angle wrapping);
* :mod:`.packing`: :class:`~.packing.Fields`, the named layout of the packed arrays.

In every law module ``pack_*`` builds the law's ``par`` (gains and model) from plain
numbers, once per controller; ``*_reference`` is the readable law (numpy, the library's
model functions) and ``*_into`` the same law compiled, one call per control tick. Both
read ``par`` (and keep their memory, ``state``, and write their result, ``out``) at the
module's named fields ``PAR_*``, ``STATE_*`` and ``OUT_*``; every ``out`` begins with the
mixer's result (:data:`.mixer.OUT_WIDTH`). A property test checks each compiled law
against its reference to 1e-9 on random inputs. The controller classes of
:mod:`tetherland.control` pack once, call the compiled law and unpack its ``out``.
"""
