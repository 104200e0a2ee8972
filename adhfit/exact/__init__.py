"""The exact incompressible neo-Hookean membrane (no large-stretch approximation)."""
