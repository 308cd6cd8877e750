"""Result files: resolved scenario, history CSV, HDF5 fields (+XDMF for ParaView), checkpoints."""
