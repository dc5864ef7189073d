"""The simulated studio: real motion, simulated cameras with a realistic 2D detector, and
simulated IMUs with the noise of real sensors; the demo's motion (`demo_motion`) and a
simulated take written as a take folder (`take_out`). Every figure is documented where it is
defined; `docs/results.md` lists them with the commands that use them."""
