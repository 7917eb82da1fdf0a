"""Speed and flux estimators: Schauder's MRAS today; the reactive-power MRAS, AFO and EKF next."""
