"""``method="mcmc"``: the posterior of one objective and its sampling (emcee).

:mod:`.posterior` (priors and the Gaussian likelihood of the least-squares residual, one
:class:`~.posterior.Target`), :mod:`.mcmc` (the sampler driver), :mod:`.chains` (the chains, their
diagnostics and their HDF5 file), :mod:`.sampling` (every slip condition's posterior from the
least-squares stage, the model probabilities, the result).  emcee and arviz load only here.
"""
