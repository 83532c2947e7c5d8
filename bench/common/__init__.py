"""What the bench scripts share: image statistics (`images`) and the Cycles
set-up of an rt-view export (`cycles`)."""
