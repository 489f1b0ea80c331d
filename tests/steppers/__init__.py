"""The steppers and the kernels under them: physics, orders, bounded work, results independent of the grid."""
