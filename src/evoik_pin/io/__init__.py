"""File formats: goals files, scene files and the YAML / JSON reading and writing they share."""
