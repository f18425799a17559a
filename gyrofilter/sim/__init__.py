"""Simulated gyros: the model-driven simulator (``simulate``), its model and checks (``model``)
and its noise terms (``noise_terms``), the motion profiles with a known truth (``profiles``), and
the hidden-effect battery that tests the gap analysis (``hidden_effects``). Uses only the core."""
