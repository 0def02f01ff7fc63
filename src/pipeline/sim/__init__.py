"""Survey simulator: the forward model every estimator is tested against."""
