"""The patients domain: models, schemas, service and router."""
