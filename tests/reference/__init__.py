"""Independent 30-digit mpmath reference of the forward model (test oracle; never imports adhfit.core)."""
