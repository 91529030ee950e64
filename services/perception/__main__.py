import sys

from services.perception.main import main

sys.exit(main())
