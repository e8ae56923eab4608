"""The hardware flow and verification runs: synthesis, place and route, proofs, tools, soak."""
