"""What the bench scripts share: image statistics (`images`), the Cycles
set-up of an rt-view export (`cycles`) and the flat terrain scene of the
coherent-ray benchmarks (`flat_scene`)."""
