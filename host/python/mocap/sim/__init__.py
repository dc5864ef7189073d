"""The simulated studio: real motion, simulated cameras with a realistic 2D detector, and
simulated IMUs with the noise of real sensors. Every figure is documented where it is
defined; `docs/results.md` (issue 3) lists them with the commands that use them."""
