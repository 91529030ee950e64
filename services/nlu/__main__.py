import sys

from services.nlu.main import main

sys.exit(main())
